#!/usr/bin/env python3
"""No source file over 1,000 lines and no function over 150 lines in libs/, apps/ and python/
(issue #30, item 6; ../shared/STYLE.md: functions that read in one screen or a few, files with one
job). Usage: check_code_size.py SOURCE_DIR. Prints every violation and exits 1 if there is any.

Functions are found from the braces of the source with comments, strings and preprocessor lines
blanked: a brace block whose head (the text since the previous `;`, `{` or `}`) holds a parameter
list and is not a control statement, a namespace, a class or an initialiser is a function, and
everything inside it (lambdas, local classes) counts towards it. The length runs from the head's
first line to the closing brace, as a reader scrolls it.
"""
import re
import subprocess
import sys
from pathlib import Path

MAX_FILE_LINES = 1000
MAX_FUNCTION_LINES = 150
CONTROL = re.compile(r"^(if|for|while|switch|catch|else|do|try)\b")
TYPE = re.compile(r"\b(namespace|class|struct|enum|union)\b")


def blank(src):
    """`src` with comments, string and character literals and preprocessor lines emptied (newlines kept)."""
    out, i, n = [], 0, len(src)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            i = n if j < 0 else j
        elif src.startswith("/*", i):
            j = src.find("*/", i + 2)
            out.append("\n" * src[i:j + 2].count("\n"))
            i = j + 2
        elif src.startswith('R"', i):
            delim = re.match(r'R"([^(]*)\(', src[i:]).group(1)
            j = src.find(")" + delim + '"', i) + len(delim) + 2
            out.append('""' + "\n" * src[i:j].count("\n"))
            i = j
        elif src[i] == '"' or (src[i] == "'" and not (i > 0 and src[i - 1].isalnum())):
            quote, j = src[i], i + 1
            while j < n and src[j] != quote:
                j += 2 if src[j] == "\\" else 1
            out.append(quote * 2)
            i = j + 1
        else:
            out.append(src[i])
            i += 1
    return "\n".join("" if line.lstrip().startswith("#") else line for line in "".join(out).split("\n"))


def functions(text):
    """(length in lines, first line, head) of every outermost function body in `text`."""
    s = blank(text)
    found, stack, last = [], [], 0
    for m in re.finditer(r"[{};]", s):
        p = m.start()
        if m.group() == "{":
            head = " ".join(s[last:p].split())
            before_paren = head.split("(")[0]
            is_function = (")" in head and not CONTROL.match(head) and "=" not in before_paren
                           and not TYPE.search(before_paren) and not any(k == "function" for k, _, _ in stack))
            first = s.count("\n", 0, p) + 1 - s[last:p].strip("\n").count("\n") if head else s.count("\n", 0, p) + 1
            stack.append(("function" if is_function else "block", first, head[:90]))
        elif m.group() == "}" and stack:
            kind, first, head = stack.pop()
            if kind == "function":
                found.append((s.count("\n", 0, p) + 1 - first + 1, first, head))
        last = p + 1
    return found


def main(root):
    files = subprocess.run(["git", "ls-files", "libs", "apps", "python"], cwd=root, capture_output=True, text=True,
                           check=True).stdout.split()
    problems = []
    for name in files:
        if not name.endswith((".cpp", ".hpp")):
            continue
        text = (Path(root) / name).read_text(encoding="utf-8")
        lines = text.count("\n")
        if lines > MAX_FILE_LINES:
            problems.append(f"{name}: {lines} lines (at most {MAX_FILE_LINES})")
        for length, first, head in functions(text):
            if length > MAX_FUNCTION_LINES:
                problems.append(f"{name}:{first}: a function of {length} lines (at most {MAX_FUNCTION_LINES}): {head}")
    for p in problems:
        print("check_code_size:", p)
    print(f"check_code_size: {len(files)} files checked, {len(problems)} over the limits")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
