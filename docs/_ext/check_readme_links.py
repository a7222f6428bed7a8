#!/usr/bin/python3
"""Fails when a relative link or picture in README.md names a file that does not exist.

The docs site checks its own pages' links; the README is read on GitHub, outside it.
Usage: check_readme_links.py [README.md]
"""
import re
import sys
from pathlib import Path

readme = Path(sys.argv[1] if len(sys.argv) > 1 else "README.md")
bad = []
for n, line in enumerate(readme.read_text().splitlines(), 1):
    for target in re.findall(r"\]\(([^)\s]+)\)", line):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        if not (readme.parent / target.split("#")[0]).exists():
            bad.append(f"{readme}:{n}: no file {target}")
print("\n".join(bad), file=sys.stderr) if bad else None
sys.exit(1 if bad else 0)
