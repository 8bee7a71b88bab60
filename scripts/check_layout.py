#!/usr/bin/env python3
"""The house rules a person can check by eye but a test checks for good.

  python3 scripts/check_layout.py sizes   [ROOT]   files <= 800 lines, functions <= 150
  python3 scripts/check_layout.py depends [ROOT]   which library includes what

sizes: a source file over MAX_FILE_LINES lines needs a comment starting
"// long:" in its first 30 lines; a function (or lambda) body over
MAX_FUNCTION_LINES lines needs one within the three lines above its
signature or the first three lines of its body. The reason is the comment.

depends: each library (a folder with include/geoanchor/<name>/ and src/)
may include only the headers of the libraries below it (ALLOWED); among
libraries only crs/ includes PROJ, and las/ includes neither PROJ nor a JSON
header. tests/, bench/ and fuzz/ are not checked: they may use PROJ as an
independent reference.

Prints each violation as path:line: message and exits 1 if there is one.
"""
import pathlib
import re
import sys

MAX_FILE_LINES = 800
MAX_FUNCTION_LINES = 150
SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".inc"}
SIZE_FOLDERS = ["base", "geodesy", "crs", "las", "io", "solver", "workflow", "gui", "cli", "tests", "bench", "fuzz"]

# Library -> the libraries of ours it may include (directly or not).
ALLOWED = {
    "base": set(),
    "geodesy": {"base"},
    "crs": {"base", "geodesy"},
    "las": {"base"},
    "solver": {"base", "geodesy"},
    "io": {"base", "geodesy", "crs", "las"},
    "workflow": {"base", "geodesy", "crs", "las", "io", "solver"},
    "gui": {"base", "geodesy", "crs", "las", "io", "solver", "workflow"},
    "cli": {"base", "geodesy", "crs", "las", "io", "solver", "workflow", "gui"},
}
PROJ_HEADER = re.compile(r'^\s*#\s*include\s*[<"](proj\.h|proj/[^>"]*|proj_[a-z_]*\.h)[>"]')
JSON_HEADER = re.compile(r'^\s*#\s*include\s*[<"](nlohmann/[^>"]*|json/[^>"]*|rapidjson/[^>"]*|simdjson\.h)[>"]')
OUR_HEADER = re.compile(r'^\s*#\s*include\s*[<"]geoanchor/([a-z_]+)/')
CONTROL = re.compile(r'^(if|for|while|switch|catch|else|do|try|return|case)\b')
NOT_FUNCTION = re.compile(r'\b(namespace|class|struct|union|enum)\b')
QUALIFIERS = re.compile(r'\)\s*((const|noexcept(\([^()]*\))?|override|final|mutable|volatile|&&?)\s*)*(->\s*[\w:<>,\s*&]+)?$')


def sources(root, folders):
    for folder in folders:
        base = root / folder
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*")):
            if path.suffix in SOURCE_SUFFIXES and path.is_file():
                yield path


def strip_code(text):
    """The text with comments, strings and character literals blanked
    (newlines kept, so that offsets and line numbers still hold)."""
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
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            open_paren = text.find("(", i + 2)
            delimiter = text[i + 2:open_paren]
            end = text.find(")" + delimiter + '"', open_paren)
            j = n if end < 0 else end + len(delimiter) + 2
            out.append('R"' + re.sub(r"[^\n]", " ", text[i + 2:j - 1]) + '"')
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # digit separator 1'000
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else c)
            i = j
        elif c == "#" and (i == 0 or text[i - 1] == "\n" or text[text.rfind("\n", 0, i) + 1:i].strip() == ""):
            # A preprocessor line (with its continuations) is not code here.
            j = i
            while True:
                j = text.find("\n", j)
                if j < 0 or text[j - 1] != "\\":
                    break
                j += 1
            j = n if j < 0 else j
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(code):
    """(head_line, open_line, close_line) of each function or lambda body, 0-based lines."""
    stack = []  # (is_function, open_offset, head_offset)
    found = []
    last_break = 0
    parens = 0
    for offset, c in enumerate(code):
        if c == "(":
            parens += 1
        elif c == ")":
            parens = max(0, parens - 1)
        elif c == ";" and parens == 0:
            last_break = offset + 1
        elif c == "{":
            head = " ".join(code[last_break:offset].split())
            # A constructor's member initialiser "x_{a}" ends its own brace
            # pair; keep the head from the signature.
            is_function = bool(head) and not NOT_FUNCTION.search(head.split("(")[0]) \
                and not CONTROL.match(head) and bool(QUALIFIERS.search(head)) \
                and not head.endswith("= ()")
            head_offset = last_break + (len(code[last_break:offset]) - len(code[last_break:offset].lstrip()))
            stack.append((is_function, offset, head_offset))
            last_break = offset + 1
        elif c == "}":
            if stack:
                is_function, open_offset, head_offset = stack.pop()
                if is_function:
                    found.append((code.count("\n", 0, head_offset), code.count("\n", 0, open_offset),
                                  code.count("\n", 0, offset)))
            last_break = offset + 1
    return found


def check_sizes(root):
    problems = []
    for path in sources(root, SIZE_FOLDERS):
        text = path.read_text(encoding="utf-8", errors="replace")
        lines = text.split("\n")
        relative = path.relative_to(root)
        if len(lines) - 1 > MAX_FILE_LINES and not any("// long:" in line for line in lines[:30]):
            problems.append(f"{relative}:1: {len(lines) - 1} lines (at most {MAX_FILE_LINES} without a '// long:' reason in its first 30 lines)")
        for head_line, open_line, close_line in functions(strip_code(text)):
            body = close_line - open_line + 1
            if body <= MAX_FUNCTION_LINES:
                continue
            window = lines[max(0, head_line - 3):open_line + 4]
            if any("// long:" in line for line in window):
                continue
            signature = " ".join(lines[head_line].split())[:80]
            problems.append(f"{relative}:{head_line + 1}: function of {body} lines (at most {MAX_FUNCTION_LINES} without a '// long:' reason at its top): {signature}")
    return problems


def check_depends(root):
    problems = []
    for library, allowed in ALLOWED.items():
        for path in sources(root, [library]):
            relative = path.relative_to(root)
            for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").split("\n"), 1):
                ours = OUR_HEADER.match(line)
                if ours and ours.group(1) != library and ours.group(1) not in allowed:
                    problems.append(f"{relative}:{number}: {library}/ includes geoanchor/{ours.group(1)}/ (allowed: {', '.join(sorted(allowed)) or 'none of ours'})")
                if PROJ_HEADER.match(line) and library != "crs":
                    problems.append(f"{relative}:{number}: {library}/ includes a PROJ header (only crs/ talks to PROJ)")
                if JSON_HEADER.match(line) and library == "las":
                    problems.append(f"{relative}:{number}: las/ includes a JSON header (the codec carries no JSON)")
    return problems


def main(argv):
    if len(argv) < 2 or argv[1] not in ("sizes", "depends"):
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    root = pathlib.Path(argv[2] if len(argv) > 2 else pathlib.Path(__file__).resolve().parent.parent)
    problems = check_sizes(root) if argv[1] == "sizes" else check_depends(root)
    for problem in problems:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
