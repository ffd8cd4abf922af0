#!/usr/bin/env python3
"""Checks every link to the project's docs: in the Markdown pages (README.md, docs/*.md) and in
the sources' strings and comments (a message that sends the user to a section must find it).

    check_doc_links.py ROOT

A link is `[text](file.md#section)`, `[text](#section)` or, in sources, `docs/file.md#section`
or `file.md#section`. The file must exist and the section must be a heading of it, by the
anchors GitHub makes of headings (lower case; punctuation but hyphens and underscores dropped;
spaces to hyphens; a repeated heading numbered -1, -2, ...). Links to other sites are not
followed. Prints each broken link with its file and line; exits 1 if any.
"""
import os
import re
import sys

LINK = re.compile(r'\]\(([^)\s]+)\)')
SOURCE_LINK = re.compile(r'(?<![\w/.-])((?:docs/)?[A-Za-z0-9_-]+\.md)#([A-Za-z0-9_-]+)')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')
ANCHOR = re.compile(r'<a (?:id|name)="([^"]+)"')
CONTINUATION = re.compile(r'^\s*(?://+|#+|\*|")?\s*"?([A-Za-z0-9_-]+)')
SOURCE_DIRS = ['app', 'bags', 'body', 'cosim', 'diagnose', 'io', 'pneumatics', 'study', 'bench',
               'scripts', 'scenarios', 'tests']
SKIP = {'check_doc_links.py'}  # this file's own examples
SOURCE_EXT = ('.cpp', '.h', '.py', '.yaml', '.sh', '.cmake', '.txt', '')


def slug(heading):
    text = re.sub(r'`|\*\*|\*|~~', '', heading)                 # inline markup
    text = re.sub(r'\[([^\]]*)\]\([^)]*\)', r'\1', text)        # links: their text
    text = text.strip().lower()
    text = ''.join(c for c in text if c.isalnum() or c in ' -_')
    return text.replace(' ', '-')


def anchors(path, cache={}):
    if path not in cache:
        found, seen, fence = set(), {}, False
        with open(path, encoding='utf-8') as f:
            for line in f:
                if line.lstrip().startswith('```'):
                    fence = not fence
                    continue
                if fence:
                    continue
                for a in ANCHOR.finditer(line):  # an explicit <a id="..."></a>
                    found.add(a.group(1))
                m = HEADING.match(line)
                if not m:
                    continue
                s = slug(m.group(2))
                n = seen.get(s, 0)
                found.add(s if n == 0 else '%s-%d' % (s, n))
                seen[s] = n + 1
        cache[path] = found
    return cache[path]


def check(root, where, line_no, target, base_dir, broken):
    if re.match(r'^[a-z]+:', target):  # http:, https:, mailto:
        return
    path, _, section = target.partition('#')
    file = os.path.normpath(os.path.join(base_dir, path)) if path else where
    if not os.path.exists(file):
        broken.append('%s:%d: %s: no file %s' % (os.path.relpath(where, root), line_no, target,
                                                 os.path.relpath(file, root)))
        return
    if section and file.endswith('.md') and section not in anchors(file):
        broken.append('%s:%d: %s: %s has no section #%s' % (
            os.path.relpath(where, root), line_no, target, os.path.relpath(file, root), section))


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else '.')
    docs = os.path.join(root, 'docs')
    broken = []
    pages = [os.path.join(root, 'README.md')] + sorted(
        os.path.join(docs, f) for f in os.listdir(docs) if f.endswith('.md'))
    links = 0
    for page in pages:
        fence = False
        with open(page, encoding='utf-8') as f:
            for n, line in enumerate(f, 1):
                if line.lstrip().startswith('```'):
                    fence = not fence
                if fence:
                    continue
                for m in LINK.finditer(line):
                    links += 1
                    check(root, page, n, m.group(1), os.path.dirname(page), broken)
    for d in SOURCE_DIRS:
        for dirpath, _, files in os.walk(os.path.join(root, d)):
            for name in files:
                if not name.endswith(SOURCE_EXT) or name.endswith('.md') or name in SKIP:
                    continue
                path = os.path.join(dirpath, name)
                try:
                    with open(path, encoding='utf-8') as f:
                        text = f.read()
                except (UnicodeDecodeError, OSError):
                    continue
                lines = text.split('\n')
                for n, line in enumerate(lines, 1):
                    for m in SOURCE_LINK.finditer(line):
                        links += 1
                        page, section = m.group(1), m.group(2)
                        page = page if page.startswith('docs/') else 'docs/' + page
                        # A section cut at a line's end by a hyphen goes on on the next line.
                        if section.endswith('-') and not line[m.end():].strip(' "\\n') and \
                                n < len(lines):
                            c = CONTINUATION.match(lines[n])
                            if c:
                                section += c.group(1)
                        check(root, path, n, page + '#' + section, root, broken)
    for b in broken:
        print(b)
    print('doc links: %d checked, %d broken' % (links, len(broken)))
    return 1 if broken else 0


if __name__ == '__main__':
    sys.exit(main())
