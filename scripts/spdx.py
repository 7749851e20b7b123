#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Every source file carries an SPDX licence identifier in its first lines.

  scripts/spdx.py --check   list the source files without one; exit 1 if any (part of make test)
  scripts/spdx.py --add     add `SPDX-License-Identifier: BSD-3-Clause` where it is missing

Source files: the repository's C, C++, Python, shell and make files (git ls-files plus new files
not ignored). Third-party fixtures and data files keep their own licences (their README.md files).
"""
import os
import subprocess
import sys

ID = "SPDX-License-Identifier: BSD-3-Clause"
COMMENT = {".c": "/* %s */", ".h": "/* %s */", ".cpp": "// %s", ".hpp": "// %s", ".py": "# %s",
           ".sh": "# %s", ".mk": "# %s"}
NAMED = {"Makefile": "# %s", "run": "# %s"}   # Makefile, libcyl/Makefile, .ci/run


def sources(root):
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"], cwd=root,
                         capture_output=True, text=True, check=True).stdout.split("\n")
    for f in out:
        if not f or not os.path.isfile(os.path.join(root, f)):
            continue
        base, ext = os.path.basename(f), os.path.splitext(f)[1]
        if f.startswith("tests/fuzz/corpus/"):
            continue
        style = COMMENT.get(ext) or (NAMED.get(base) if base == "Makefile" or f == ".ci/run" else None)
        if style:
            yield f, style


def has_id(path):
    with open(path, encoding="utf-8", errors="replace") as fh:
        head = [fh.readline() for _ in range(3)]
    return any("SPDX-License-Identifier:" in line for line in head)


def add(path, style):
    with open(path, encoding="utf-8") as fh:
        lines = fh.readlines()
    at = 1 if lines and lines[0].startswith("#!") else 0
    lines.insert(at, (style % ID) + "\n")
    with open(path, "w", encoding="utf-8") as fh:
        fh.writelines(lines)


def main():
    if len(sys.argv) != 2 or sys.argv[1] not in ("--check", "--add", "-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    if sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    missing = [(f, s) for f, s in sources(root) if not has_id(os.path.join(root, f))]
    if sys.argv[1] == "--add":
        for f, s in missing:
            add(os.path.join(root, f), s)
        print(f"spdx: added the identifier to {len(missing)} files")
        return 0
    for f, _ in missing:
        print(f"{f}: no SPDX-License-Identifier in its first 3 lines")
    n = sum(1 for _ in sources(root))
    print(f"spdx: {n - len(missing)} of {n} source files carry an SPDX identifier")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
