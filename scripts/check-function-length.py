#!/usr/bin/env python3
"""Lists the C++ functions longer than a limit (default 60 lines, the project's limit) in common/,
procs/, tools/ and bench/ (tests are not scanned), longest first, and their count.

  python3 scripts/check-function-length.py [--limit N] [--strict] [--except PATH:NAME ...] [ROOT]

A function's length counts every line from the first line of its signature to its closing brace
(lambdas and local classes count towards the function they are in). Exit status 0, or with
--strict 1 when any function is over the limit. --except PATH:NAME (e.g.
common/core/src/slam/landmark_map.cpp:LandmarkMap::apply) lists a function over the limit without
failing --strict: for one whose split is under way on another branch, named in the test that passes
it (tests/CMakeLists.txt), never a way to keep a long function. The scanner is lexical: comments,
string and character literals are blanked first, then braces are classified as namespace, class,
function or inner blocks by the text before them; it does not need a compiler or a build directory.
"""
import argparse
import os
import re
import sys

DIRS = ("common", "procs", "tools", "bench")
EXTS = (".cpp", ".cc", ".h", ".hpp")
FUNC_HEAD = re.compile(r"\)\s*(const|noexcept|override|final|mutable|->[^{]*|\s)*$")
INIT_LIST = re.compile(r"\)\s*(noexcept\s*)?:")
NAME = re.compile(r"([~\w:<>=!+\-*/%&|^\[\]]+)\s*\(")


def blank_comments_and_literals(text):
    """Replaces comments and string/char literals with spaces, keeping newlines (line numbers)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # digit separator 1'000
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(" " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """Yields (name, first_line, last_line) of each function definition at namespace/class scope."""
    code = blank_comments_and_literals(text)
    # Preprocessor lines are not statements.
    code = re.sub(r"(?m)^[ \t]*#.*(\\\n.*)*$", lambda m: re.sub(r"[^\n]", " ", m.group(0)), code)
    stack = []  # entries: (kind, start_offset, name)
    head_start = 0  # offset where the current declaration began (after the last ; { or })
    line_of = lambda off: code.count("\n", 0, off) + 1
    i = 0
    for i, c in enumerate(code):
        if c == ";" and (not stack or stack[-1][0] in ("namespace", "class")):
            head_start = i + 1
        elif c == "{":
            if stack and stack[-1][0] in ("function", "block", "init"):
                stack.append(("block", i, ""))
                continue
            head = code[head_start:i]
            flat = " ".join(head.split())
            if INIT_LIST.search(flat) and re.search(r"[\w>]\s*$", flat) and not FUNC_HEAD.search(flat):
                stack.append(("init", i, ""))  # member{value} in a constructor's initialiser list
                continue
            if re.search(r"\bnamespace\b|extern\s*$", flat) and "(" not in flat:
                stack.append(("namespace", i, ""))
            elif re.search(r"\b(class|struct|union|enum)\b", flat) and "(" not in flat.split("{")[0]:
                stack.append(("class", i, ""))
            elif FUNC_HEAD.search(flat) or INIT_LIST.search(flat):
                first = head_start + (len(head) - len(head.lstrip()))
                m = None
                for m in NAME.finditer(flat.split(")")[0] + ")"):
                    break
                stack.append(("function", first, m.group(1) if m else "?"))
            else:
                stack.append(("block", i, ""))  # e.g. a brace initialiser at namespace scope
        elif c == "}":
            if not stack:
                continue
            kind, start, name = stack.pop()
            if kind == "function":
                yield name, line_of(start), line_of(i)
            if kind != "init":
                head_start = i + 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", nargs="?", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--limit", type=int, default=60, help="longest allowed function [lines] (default 60)")
    ap.add_argument("--strict", action="store_true", help="exit 1 when a function is over the limit")
    ap.add_argument("--except", dest="excepted", action="append", default=[], metavar="PATH:NAME",
                    help="a function over the limit that does not fail --strict (listed, marked 'excepted')")
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    over = []
    for d in DIRS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, d)):
            dirnames[:] = sorted(x for x in dirnames if x not in ("tests", "test", "bench", "build"))
            for f in sorted(filenames):
                if not f.endswith(EXTS):
                    continue
                path = os.path.join(dirpath, f)
                with open(path, encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                for name, a, b in functions(text):
                    if b - a + 1 > args.limit:
                        over.append((b - a + 1, os.path.relpath(path, root), a, name))
    over.sort(key=lambda t: (-t[0], t[1], t[2]))
    failing = 0
    for n, path, line, name in over:
        excepted = f"{path}:{name}" in args.excepted
        failing += 0 if excepted else 1
        print(f"{n:5d}  {path}:{line}  {name}" + ("  (excepted)" if excepted else ""))
    print(f"check-function-length: {len(over)} function(s) over {args.limit} lines in {', '.join(DIRS)}"
          + (f", {len(over) - failing} of them excepted" if failing < len(over) else ""))
    return 1 if args.strict and failing else 0


if __name__ == "__main__":
    sys.exit(main())
