#!/usr/bin/env python3
"""Mutates bagsim's input files and checks what bagsim makes of them (issue 39, the fuzzer).

    fuzz_inputs.py BAGSIM WORKDIR [--cases N] [--seed S] [--timeout SEC] [--keep]

Seeds: the test scenarios (a load test, the coarse patient on the array, the coarse pneumatic
turn), the tiny study and the seed study's measured data (`bagsim diagnose`), copied into WORKDIR with their neighbours so that relative paths
resolve. Each case applies one mutation to one seed (a value's magnitude, unit or type, a
key duplicated, dropped or misspelt, a second YAML document, a path to a folder or to
/dev/zero, a file cut short, a scenario past 1 MiB or a CSV of 200 000 more rows; in 5 % of
the cases also an --out that cannot be made: under a file, /proc or /dev/null) and runs `bagsim run` (or `bagsim study`) on it with a time limit;
a run still going at the limit was accepted and is stopped with SIGTERM.

Every case must hold:
  - no crash: no exit by a signal, no abort (134), no segfault (139), no C++ terminate;
  - bad input (exit 2) leaves no output folder and its message names where: a file and
    line, a key ('key ...' or --set KEY) or an option;
  - no message names C++ internals (std::, a :: scope, bad_alloc, what(), YAML::, Eigen);
  - a run stopped by SIGTERM ends within 10 s with 143;
  - exit statuses are the documented ones: 0, 1, 2, 3, 129, 130, 143;
  - an --out that cannot be made never ends 0, and the file in its way is left as it was.
Prints a line per failure (the mutation, the status, the first line of the message) and a
summary of the classes found; exits 1 if any case failed.
"""
import argparse
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SCENARIOS = os.path.join(HERE, '..', '..', 'scenarios', 'tests')
SEEDS = [  # (file, command, weight)
    ('tiny-load-test.yaml', 'run', 5),
    ('tiny-study.yaml', 'study', 2),
    ('supine-on-array-coarse.yaml', 'run', 2),
    ('turn-left-pneumatic-coarse.yaml', 'run', 2),
    ('measured', 'diagnose', 2),  # the seed study's measured data (its manifest or CSV)
]
INTERNAL = re.compile(r'std::|\b[A-Za-z_]\w*::[A-Za-z_]|bad_alloc|what\(\)|YAML::|Eigen|'
                      r'terminate called|basic_string|Assertion .* failed')
WHERE = re.compile(r"key '|--set |\.yaml:\d+|\.csv\b|--[a-z-]+|option|usage:|scenario file|"
                   r"error: /\S+: ")  # the last: a file the input named, by its path
LINE = re.compile(r'^(\s*(?:-\s+)?)([A-Za-z_][\w.]*)(\s*:\s*)([^#{\[\n][^#\n]*?)(\s*(?:#.*)?)$')
NUMBER = re.compile(r'[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?')
MAGNITUDES = ['1e-300', '1e300', '1e400', '-1e400', '0', '-1', '-0', 'nan', '.nan', 'inf',
              '.inf', '-.inf', '1e-12', '1e12', '2147483648', '99999999999999999999', '0x10']
TYPES = ['[1, 2, 3]', '{a: 1}', 'yes', '~', "''", '""', 'true', '[]', '{}', '"1 2 3"',
         '[' + ', '.join(['1 g'] * 5000) + ']', 'x' * 5000, '!!binary aGVsbG8=', '&a 1',
         '*undefined']
UNITS = ['kg/m', 'furlong', 'mm/min^2', 'degF', 'K', 'Pa/m', 'N/mm', 's', '%', 'mmHg', 'g/s']
PATHS = ['/dev/zero', '/tmp', '.', '..', '/nonexistent/x.csv', '/proc/self/mem', '']


def mutate(text, rng):
    """One mutation of a scenario's text: (new text, what was done)."""
    lines = text.split('\n')
    keyed = [i for i, l in enumerate(lines) if LINE.match(l)]
    kind = rng.choice(['magnitude', 'magnitude', 'unit', 'type', 'duplicate', 'drop', 'misspell',
                       'document', 'path', 'cut', 'garbage', 'huge'])
    if kind == 'huge':  # past the scenario reader's 1 MiB: refused without being read
        return text + '\n' + ('# ' + 'x' * 98 + '\n') * 11000, 'padded to %d bytes' % (
            len(text) + 1100001)
    if kind == 'document':
        return text + '\n---\nkind: seed-load-test\n', 'a second YAML document'
    if kind == 'cut':
        at = rng.randrange(1, max(2, len(text)))
        return text[:at], 'cut at byte %d' % at
    if kind == 'garbage':
        at = rng.randrange(0, max(1, len(text)))
        junk = rng.choice(['\0', '\t', ':', '- ', '{', ']', '"', '\x7f', '\xff', '\u00e9', '%'])
        return text[:at] + junk + text[at:], 'inserted %r at byte %d' % (junk, at)
    if not keyed:
        return text + '\nunknown_key: 1\n', 'an unknown key'
    i = rng.choice(keyed)
    m = LINE.match(lines[i])
    indent, key, colon, value, rest = m.groups()
    if kind == 'magnitude':
        n = NUMBER.search(value)
        new = rng.choice(MAGNITUDES)
        value2 = value[:n.start()] + new + value[n.end():] if n else new
        lines[i] = indent + key + colon + value2 + rest
        what = '%s: %r -> %r' % (key, value, value2)
    elif kind == 'unit':
        n = NUMBER.search(value)
        value2 = (value[:n.end()] if n else '1') + ' ' + rng.choice(UNITS)
        lines[i] = indent + key + colon + value2 + rest
        what = '%s: %r -> %r' % (key, value, value2)
    elif kind == 'type':
        value2 = rng.choice(TYPES)
        lines[i] = indent + key + colon + value2 + rest
        what = '%s: %r -> %s' % (key, value, value2[:40])
    elif kind == 'path':
        value2 = rng.choice(PATHS)
        lines[i] = indent + key + colon + value2 + rest
        what = '%s: %r -> %r' % (key, value, value2)
    elif kind == 'duplicate':
        lines.insert(i + 1, lines[i])
        what = '%s given twice' % key
    elif kind == 'drop':
        del lines[i]
        what = '%s dropped' % key
    else:
        j = rng.randrange(len(key))
        key2 = key[:j] + key[j + 1:] if len(key) > 1 else key + 'x'
        lines[i] = indent + key2 + colon + value + rest
        what = '%s misspelt %s' % (key, key2)
    return '\n'.join(lines), what


MEASURED = os.path.join(HERE, '..', '..', 'scenarios', 'measured', 'seed-study')
CELL = re.compile(r'(?<![\w.])[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(?![\w.])')


def mutate_measured(workdir, k, rng):
    """A copy of the seed study's measured data with its manifest or its CSV mutated: (its
    folder, what was done)."""
    folder = os.path.join(workdir, 'measured-%05d' % k)
    shutil.copytree(MEASURED, folder)
    manifest = os.path.join(folder, 'measured.yaml')
    with open(manifest, encoding='utf-8') as f:
        text = f.read().replace('scenario: ../../seed-load-test.yaml', 'scenario: ' +
                                os.path.abspath(os.path.join(MEASURED, '..', '..',
                                                             'seed-load-test.yaml')))
    csv = os.path.join(folder, 'stiffness.csv')
    if rng.random() < 0.5:
        text, what = mutate(text, rng)
        what = 'measured.yaml ' + what
    else:
        with open(csv, encoding='utf-8') as f:
            rows = f.read().split('\n')
        data = [i for i, r in enumerate(rows) if r and not r.startswith('#') and CELL.search(r)]
        op = rng.choice(['cell', 'cell', 'cell', 'drop-column', 'empty', 'duplicate-header',
                         'extra-cell', 'huge'])
        if op == 'cell' and data:
            i = rng.choice(data)
            cells = list(CELL.finditer(rows[i]))
            c = rng.choice(cells)
            new = rng.choice(MAGNITUDES + ['', 'x', '1,2', '"3"'])
            rows[i] = rows[i][:c.start()] + new + rows[i][c.end():]
            what = 'stiffness.csv line %d: %r -> %r' % (i + 1, c.group(0), new)
        elif op == 'drop-column':
            rows = [','.join(r.split(',')[:-1]) if not r.startswith('#') else r for r in rows]
            what = 'stiffness.csv without its last column'
        elif op == 'empty':
            rows = []
            what = 'stiffness.csv empty'
        elif op == 'huge':  # 200 000 more rows of the last one: read, limited or stopped
            last = rows[data[-1]] if data else '1,1'
            rows += [last] * 200000
            what = 'stiffness.csv with 200 000 more rows'
        elif op == 'duplicate-header':
            head = next((i for i, r in enumerate(rows) if r and not r.startswith('#')), 0)
            rows.insert(head + 1, rows[head])
            what = 'stiffness.csv header twice'
        else:
            i = rng.choice(data) if data else 0
            rows[i] = rows[i] + ',1'
            what = 'stiffness.csv line %d with an extra cell' % (i + 1)
        with open(csv, 'w', encoding='utf-8') as f:
            f.write('\n'.join(rows))
    with open(manifest, 'w', encoding='utf-8', errors='surrogateescape') as f:
        f.write(text)
    return folder, what


def unwritable_out(workdir, k, rng):
    """An --out the program cannot make (it runs as root in CI, so no mode bits): under a
    file, under /proc, or under /dev/null: (the path, what it is)."""
    blocker = os.path.join(workdir, 'file-%05d' % k)
    with open(blocker, 'w', encoding='utf-8') as f:
        f.write('the user\'s file, not a folder\n')
    return rng.choice([(os.path.join(blocker, 'out'), '--out under a file'),
                       ('/proc/bagsim-fuzz-out-%d' % k, '--out under /proc'),
                       ('/dev/null/out', '--out under /dev/null')]), blocker


def run_case(bagsim, command, path, out, timeout):
    """(exit status or None, stopped by us, stdout + stderr, seconds)."""
    if command == 'diagnose':
        cmd = [bagsim, 'diagnose', '--measured', path, '--out', out, '--quiet']
    else:
        cmd = [bagsim, command, path, '--out', out]
    if command == 'run':
        cmd.append('--quiet')
    start = time.time()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         start_new_session=True)
    stopped = False
    try:
        out_text, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        stopped = True
        os.killpg(p.pid, signal.SIGTERM)
        try:
            out_text, _ = p.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            out_text, _ = p.communicate()
            return None, True, out_text.decode('utf-8', 'replace'), time.time() - start
    return p.returncode, stopped, out_text.decode('utf-8', 'replace'), time.time() - start


def judge(rc, stopped, text, out):
    """The classes of what is wrong ([] if nothing)."""
    wrong = []
    if rc is None:
        return ['did not stop within 10 s of SIGTERM']
    if rc < 0 and not (stopped and rc == -signal.SIGTERM):
        wrong.append('crash: killed by signal %d' % -rc)
    if rc in (134, 136, 139) or 'terminate called' in text:
        wrong.append('crash: exit %d' % rc)
    if rc not in (0, 1, 2, 3, 129, 130, 143) and rc >= 0:
        wrong.append('undocumented exit status %d' % rc)
    if stopped and rc not in (143, -signal.SIGTERM, 0, 1, 3):
        wrong.append('SIGTERM gave exit %d' % rc)
    if INTERNAL.search(text):
        wrong.append('internal name in the message')
    if rc == 2:
        if os.path.exists(out):
            wrong.append('bad input left an output folder')
        if not WHERE.search(text):
            wrong.append('bad input message names no file, line, key or option')
    return wrong


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('bagsim')
    ap.add_argument('workdir')
    ap.add_argument('--cases', type=int, default=200)
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--timeout', type=float, default=2.0)
    ap.add_argument('--keep', action='store_true', help='keep the failing inputs in WORKDIR')
    a = ap.parse_args()
    rng = random.Random(a.seed)
    shutil.rmtree(a.workdir, ignore_errors=True)
    os.makedirs(a.workdir)
    for f in os.listdir(SCENARIOS):  # the seeds' neighbours (a study's base scenario)
        if f.endswith('.yaml'):
            shutil.copy(os.path.join(SCENARIOS, f), a.workdir)
    seeds = []
    for name, command, weight in SEEDS:
        text = ''
        if command != 'diagnose':
            with open(os.path.join(SCENARIOS, name), encoding='utf-8') as f:
                text = f.read()
        seeds += [(name, command, text)] * weight
    classes, failures, statuses = {}, 0, {}
    unwritable, huge = 0, 0
    start = time.time()
    for k in range(a.cases):
        name, command, text = rng.choice(seeds)
        if command == 'diagnose':
            path, what = mutate_measured(a.workdir, k, rng)
        else:
            mutant, what = mutate(text, rng)
            path = os.path.join(a.workdir, 'case-%05d.yaml' % k)
            with open(path, 'w', encoding='utf-8', errors='surrogateescape') as f:
                f.write(mutant)
        out = os.path.join(a.workdir, 'out-%05d' % k)
        blocker = None
        if rng.random() < 0.05:  # the input as it is or mutated, the output place unwritable
            (out, where), blocker = unwritable_out(a.workdir, k, rng)
            what += '; ' + where
            unwritable += 1
        huge += 'padded to' in what or '200 000 more rows' in what
        rc, stopped, out_text, secs = run_case(a.bagsim, command, path, out, a.timeout)
        key = 'stopped' if stopped else str(rc)
        statuses[key] = statuses.get(key, 0) + 1
        wrong = judge(rc, stopped, out_text, out)
        if blocker:
            with open(blocker, encoding='utf-8') as f:
                if f.read() != 'the user\'s file, not a folder\n':
                    wrong.append('the user\'s file in the way of --out was changed')
            if rc == 0 and not stopped:
                wrong.append('exit 0 with an output folder that cannot be made')
            os.remove(blocker)
        for w in wrong:
            classes[w] = classes.get(w, 0) + 1
        if wrong:
            failures += 1
            first = next((l for l in out_text.splitlines() if l.strip()), '')
            print('FAIL case %d (%s, %s): %s -> exit %s%s; %s\n    %s' %
                  (k, name, command, what, rc, ' after SIGTERM' if stopped else '',
                   '; '.join(wrong), first[:300]))
        if not (wrong and a.keep):
            shutil.rmtree(path) if os.path.isdir(path) else os.remove(path)
        shutil.rmtree(out, ignore_errors=True)
    print('fuzz: %d cases in %.0f s (seed %d; %d with an --out that cannot be made, %d with a '
          'huge file); exit statuses %s; %d failed' %
          (a.cases, time.time() - start, a.seed, unwritable, huge,
           ', '.join('%s: %d' % kv for kv in sorted(statuses.items())), failures))
    for c, n in sorted(classes.items(), key=lambda kv: -kv[1]):
        print('  %5d  %s' % (n, c))
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
