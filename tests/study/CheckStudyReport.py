#!/usr/bin/env python3
"""Checks report.html of scenarios/tests/tiny-study.yaml (the test study_tiny_report): a row per
case with its status, the two failed cases named with their reason, the outputs drawn against
each swept parameter, the load-displacement curves of the cases that wrote them, the study's
text; nothing fetched. Usage: CheckStudyReport.py REPORT.html"""
import re
import sys
from html.parser import HTMLParser


class Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tables = {}       # id -> rows of cell texts
        self.table = None
        self.row = None
        self.cell = None
        self.svg_titles = []   # the <title> of each top-level svg
        self.svg_depth = 0
        self.in_title = False
        self.title = ''

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == 'table':
            self.table = a.get('id', '')
            self.tables[self.table] = []
        elif tag == 'tr' and self.table is not None:
            self.row = []
        elif tag in ('td', 'th') and self.row is not None:
            self.cell = ''
        elif tag == 'svg':
            self.svg_depth += 1
            if self.svg_depth == 1:
                self.svg_titles.append(None)
        elif tag == 'title' and self.svg_depth == 1 and self.svg_titles[-1] is None:
            self.in_title = True
            self.title = ''

    def handle_endtag(self, tag):
        if tag == 'table':
            self.table = None
        elif tag == 'tr' and self.row is not None:
            self.tables[self.table].append(self.row)
            self.row = None
        elif tag in ('td', 'th') and self.cell is not None:
            self.row.append(self.cell.strip())
            self.cell = None
        elif tag == 'svg':
            self.svg_depth -= 1
        elif tag == 'title' and self.in_title:
            self.svg_titles[-1] = self.title
            self.in_title = False

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data
        if self.in_title:
            self.title += data


text = open(sys.argv[1], encoding='utf-8').read()
page = Page()
page.feed(text)
cases = page.tables['cases']
assert cases[0][:5] == ['case', 'contact.penalty [Pa/m]', 'solver.max_iterations',
                        'solver.stabilization [Pa/m]', 'status'], cases[0]
assert [r[0] for r in cases[1:]] == ['1', '2', '3', '4'], cases
assert [r[4] for r in cases[1:]] == ['\u2714 ok', '\u2718 failed', '\u2714 ok', '\u2718 failed'], cases
problems = page.tables['problem-cases']
assert [r[0] for r in problems[1:]] == ['2', '4'], problems
assert all('no convergence while inflating' in r[3] for r in problems[1:]), problems
assert 'INCOMPLETE STUDY' not in text
assert '2 ok, 0 partial, 2 failed, 0 not run, 0 interrupted' in text
assert 'tiny load test, two contact penalties x a working and a failing solver' in text
assert 'kind: seed-load-test' in text  # the base scenario as run

# Three swept parameters with numbers, two of them zipped (one to one: drawn once, on the
# first, the other named with it) x three numeric outputs; then the load-displacement curves
# of the two cases that ran.
titles = page.svg_titles
curves = [t for t in titles if ' against ' in t and not t.startswith('Force against')]
expected = [o + ' against ' + p
            for p in ('contact penalty', 'solver.max_iterations, solver.stabilization with it')
            for o in ('stiffness at gas mass 3.5 g', 'r\u00b2 (min)', 'force (max)')]
assert curves == expected, curves
ld = [t for t in titles if t.startswith('Force against displacement')]
assert ld == ['Force against displacement, cases 1 to 3'], ld
assert 'case 1: penalty=1e7 Pa/m' in text and 'case 3: penalty=1e8 Pa/m' in text
assert 'contact penalty [1e7 Pa/m]' in text
assert 'stiffness at gas mass 3.5 g [N/mm]' in text and '>force [N]<' in text
assert len(titles) == len(expected) + len(ld), titles
assert "class='map'" not in text
assert not re.search(r'''(src|href)\s*=\s*['"]?\s*(https?:)?//''', text)
assert '<script' not in text
print('report.html: %d case rows, %d pictures: ok' % (len(cases) - 1, len(titles)))
