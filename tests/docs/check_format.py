#!/usr/bin/env python3
"""Every C++ source and header the repository tracks is as clang-format leaves it (.clang-format
at the top; clang-format 14, Debian's). Prints each file that is not, with the first lines
clang-format would change, and exits 1; exits 0 when all are. Outside a git checkout it checks
every *.cpp and *.h under SOURCE_DIR but build folders and hidden ones. Without clang-format it
says so and exits 1 (scripts/setup installs it).

    python3 tests/docs/check_format.py SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys


def list_sources(root):
    try:
        return subprocess.run(["git", "-C", root, "ls-files", "*.cpp", "*.h"], check=True,
                              capture_output=True, text=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        found = []
        for d, dirs, names in os.walk(root):
            dirs[:] = sorted(x for x in dirs if not x.startswith(".") and not x.startswith("build"))
            found += [os.path.relpath(os.path.join(d, n), root) for n in sorted(names)
                      if n.endswith((".cpp", ".h"))]
        return found


def main() -> int:
    if len(sys.argv) != 2:
        print("usage: check_format.py SOURCE_DIR", file=sys.stderr)
        return 2
    root = sys.argv[1]
    tool = shutil.which("clang-format")
    if not tool:
        print("format check: clang-format is not installed (scripts/setup installs it)")
        return 1
    files = list_sources(root)
    if not files:
        print(f"format check: no C++ sources under {root}")
        return 1
    bad = 0
    for f in files:
        r = subprocess.run([tool, "--dry-run", "--Werror", f], cwd=root, capture_output=True,
                           text=True)
        if r.returncode != 0:
            bad += 1
            lines = [l for l in r.stderr.splitlines() if ": error:" in l][:3]
            print(f"{f}: not as clang-format leaves it; fix with: clang-format -i {f}")
            for l in lines:
                print("  " + l)
    print(f"format check: {len(files)} files, {bad} not formatted")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
