#!/usr/bin/python3
"""Removes Doxygen's links to header files from its XML (docs/Doxyfile writes no file pages).

Usage: strip_file_refs.py XML_DIR. A comment that names a header (`bvh.hpp`), and a class's include line,
become links to that file's page in Doxygen's XML; the docs site has one page for the namespace and none per
file, so the link would be a broken reference. The text stays.
"""
import re
import sys
from pathlib import Path

REF = re.compile(r'<ref refid="[^"]*_8hpp[^"]*" kindref="compound">(.*?)</ref>', re.S)
INCLUDES = re.compile(r'<includes refid="[^"]*_8hpp[^"]*" ')
for path in Path(sys.argv[1]).glob("*.xml"):
    text = path.read_text()
    new = INCLUDES.sub("<includes ", REF.sub(r"\1", text))
    if new != text:
        path.write_text(new)
