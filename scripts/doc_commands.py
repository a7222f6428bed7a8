#!/usr/bin/python3
"""Runs the commands of the README and the user guide, as a user would, in order.

Usage: scripts/doc_commands.py --build BUILD_DIR [--keep DIR] [--list] [--no-python] FILE.md...

Which blocks run:
  - in README.md, every fenced ``sh`` and ``python`` block;
  - in other pages, the blocks right after a line starting ``<!-- test`` (an HTML comment
    that neither GitHub nor the docs site shows).
Within a ``sh`` block each command runs on its own (lines ending in ``\\`` continue it;
lines that are only a comment are skipped), with bash, in one temporary directory for all
the files given, so later commands use earlier outputs. In that directory ``build`` links
to the build folder and ``examples``, ``tests``, ``scripts`` to the source tree, so
commands run exactly as written.

A command's trailing comment may say how the test runs it:
  ``# test: skip``            not run (say why in the comment before ``test:``)
  ``# test: --rows 4 --max-time 0.02 --no-render``
                              each option given replaces the command's value of it, or is
                              added (a flag, or an option the command does not give)
In a ``python`` block (run as one script by /usr/bin/python3 with PYTHONPATH=BUILD/python),
``# test: rows=4, max_time=0.02`` replaces those keyword arguments' values on that line.
The marker may follow other text in the comment: ``# about 10 s; test: --max-time 0.05``.
A failure prints the file, the line and the command as it was run, and exits 1.
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FENCE = re.compile(r"^```(\w+)\s*$")
MARKER = re.compile(r"(?:^|[\s;#])test:\s*(.*?)\s*$")


def blocks(path):
    """Yields (language, first line number, [lines]) of the blocks that run."""
    lines = path.read_text().splitlines()
    readme = path.name == "README.md"
    marked = False
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("<!-- test"):
            marked = True
        m = FENCE.match(line)
        if m:
            lang, start, body = m.group(1), i + 2, []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            if lang in ("sh", "python") and (readme or marked):
                yield lang, start, body
            marked = False
        elif line.strip() and not line.startswith("<!--"):
            marked = False
        i += 1


def split_comment(line):
    """(code, comment) of one shell line: the comment is from the first # outside quotes."""
    quote = None
    for k, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (k == 0 or line[k - 1].isspace()):
            return line[:k].rstrip(), line[k + 1:]
    return line.rstrip(), ""


def marker(comment):
    m = MARKER.search(comment)
    return m.group(1) if m else None


def shell_commands(start, body):
    """Yields (line number, command text, test marker or None) of a sh block."""
    k = 0
    while k < len(body):
        first = k
        code, comment = split_comment(body[k])
        parts, test = [], marker(comment)
        while code.endswith("\\") and k + 1 < len(body):
            parts.append(code[:-1].rstrip())
            k += 1
            code, comment = split_comment(body[k])
            test = marker(comment) or test
        parts.append(code)
        k += 1
        command = " ".join(p.strip() for p in parts if p.strip())
        if command:
            yield start + first, command, test


def apply_options(command, test):
    """The command with the options of a test marker replacing or added to its own."""
    tokens = shlex.split(test)
    j = 0
    while j < len(tokens):
        opt = tokens[j]
        if not opt.startswith("--"):
            raise ValueError(f"test marker: {opt!r} is not an option (--name [value])")
        has_value = j + 1 < len(tokens) and not tokens[j + 1].startswith("--")
        value = tokens[j + 1] if has_value else None
        j += 2 if has_value else 1
        pattern = re.compile(r"(?<!\S)" + re.escape(opt) + r"(?:=|\s+)(?!--)(\S+)")
        if has_value and pattern.search(command):
            command = pattern.sub(lambda m: opt + " " + shlex.quote(value), command, count=1)
        elif not re.search(r"(?<!\S)" + re.escape(opt) + r"(?!\S)", command):
            command += " " + opt + ("" if value is None else " " + shlex.quote(value))
    return command


def python_script(body):
    """The block as a script, each line's keyword arguments set by its test marker."""
    out = []
    for line in body:
        code, comment = split_comment(line)
        test = marker(comment)
        if test:
            for name, value in re.findall(r"(\w+)\s*=\s*([^,]+)", test):
                pattern = re.compile(r"\b" + name + r"\s*=\s*[^,)]+")
                if not pattern.search(code):
                    raise ValueError(f"test marker: no argument {name}= on the line: {code}")
                code = pattern.sub(f"{name}={value.strip()}", code, count=1)
        out.append(code)
    return "\n".join(out) + "\n"


def run(label, argv, cwd, env):
    print(f"--- {label}\n    {' '.join(argv) if argv[0] != 'bash' else argv[-1]}", flush=True)
    t0 = time.monotonic()
    r = subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, errors="replace")
    took = time.monotonic() - t0
    if r.returncode != 0:
        print(r.stdout[-4000:])
        print(f"FAILED (exit {r.returncode}) {label}:\n    {argv[-1] if argv[0] == 'bash' else ' '.join(argv)}",
              file=sys.stderr)
        return False
    print(f"    ok, {took:.1f} s", flush=True)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", required=True, help="the build folder (holds knitsim, python/)")
    ap.add_argument("--keep", help="run in this (new or empty) directory and keep it")
    ap.add_argument("--list", action="store_true", help="print the commands as they would run")
    ap.add_argument("--no-python", action="store_true", help="skip the python blocks (no module built)")
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    build = Path(args.build).resolve()

    steps = []  # (label, kind, text)
    for name in args.files:
        path = Path(name) if Path(name).is_absolute() else ROOT / name
        rel = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
        for lang, start, body in blocks(path):
            if lang == "python":
                if args.no_python:
                    print(f"--- {rel}:{start} skipped (no Python module): python block")
                    continue
                steps.append((f"{rel}:{start} (python block)", "python", python_script(body)))
                continue
            for line, command, test in shell_commands(start, body):
                if test is not None and test.split()[:1] == ["skip"]:
                    print(f"--- {rel}:{line} skipped: {command}")
                    continue
                if test:
                    command = apply_options(command, test)
                steps.append((f"{rel}:{line}", "sh", command))
    if not steps:
        print("doc_commands: no commands found", file=sys.stderr)
        return 1
    if args.list:
        for label, kind, text in steps:
            print(f"{label}\n    {text}")
        return 0

    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="knit-doc-commands-"))
    work.mkdir(parents=True, exist_ok=True)
    if any(work.iterdir()):
        print(f"doc_commands: {work} is not empty", file=sys.stderr)
        return 1
    (work / "build").symlink_to(build)
    for name in ("examples", "tests", "scripts"):
        (work / name).symlink_to(ROOT / name)
    env = dict(os.environ, PYTHONPATH=str(build / "python"))
    ok = True
    t0 = time.monotonic()
    for label, kind, text in steps:
        if kind == "python":
            script = work / f"block_{len(list(work.glob('block_*.py')))}.py"
            script.write_text(text)
            ok = run(label, ["/usr/bin/python3", script.name], work, env)
        else:
            ok = run(label, ["bash", "-euo", "pipefail", "-c", text], work, env)
        if not ok:
            break
    print(f"doc_commands: {len(steps)} commands, {time.monotonic() - t0:.0f} s, in {work}")
    if ok and not args.keep:
        shutil.rmtree(work)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
