#!/usr/bin/env bash
# A code comment says why the code is as it is, so it must stay true as long as the code does: no
# comment of a code file may carry a date, an issue or pull-request number, or a session's history.
# The scanner reads only comments (string literals, here-documents and data files are what programs
# read, so they are left alone), and first proves on small samples that it flags and passes what it
# should, so that a broken scanner fails instead of passing everything.
# Usage: no_dated_comments_test.sh REPO_ROOT. Exit 0 clean, 1 offending comments, 2 bad usage,
# 77 (skip) when no Python 3 interpreter is found.
set -uo pipefail
src="${1:-}"
if [ -z "$src" ] || ! cd "$src" 2>/dev/null; then echo "usage: $0 REPO_ROOT"; exit 2; fi
self="tests/repo/no_dated_comments_test.sh"

python=""
for candidate in "${WEATHERGS_PYTHON3:-}" /usr/bin/python3 "$(command -v python3 2>/dev/null)"; do
  if [ -n "$candidate" ] && [ -x "$candidate" ]; then python="$candidate"; break; fi
done
[ -n "$python" ] || { echo "no python3 interpreter: skipped"; exit 77; }

work=$(mktemp -d /tmp/weathergs-comments.XXXXXX)
trap 'rm -rf "$work"' EXIT

# The scanner: reads NUL-separated paths (relative to the current folder) on stdin and prints
# FILE:LINE: comment for every offending comment; exit 1 when there is one.
cat > "$work/scan.py" <<'PY'
import io
import re
import sys
import tokenize

DATE = re.compile(
    r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b|\b(?:19|20)\d\d/[01]\d/[0-3]\d\b"
    r"|\b(?:Jan(?:uary)?|Feb(?:ruary)?|Mar(?:ch)?|Apr(?:il)?|May|June?|July?|Aug(?:ust)?"
    r"|Sep(?:t(?:ember)?)?|Oct(?:ober)?|Nov(?:ember)?|Dec(?:ember)?)\.?\s+"
    r"(?:[0-3]?\d(?:st|nd|rd|th)?,?\s+)?(?:19|20)\d\d\b")
ISSUE = re.compile(
    r"\b[Ii]ssues?\s*#?\s*\d+|\b[Ii]ssue[- ]tracker\b|\b(?:PR|[Pp]ull [Rr]equest)\s*#\s*\d+"
    r"|(?<![\w&#/$])#\d+\b")
SESSION = re.compile(r"\b(?:this|last|previous) session\b", re.I)


def offends(text):
    return DATE.search(text) or ISSUE.search(text) or SESSION.search(text)


def raw_string_at(src, i):
    """Whether a C++ raw string literal R"d(...)d" (maybe with a u8, u, U or L prefix) starts at i."""
    if not re.match(r'R"[^()\\\s]{0,16}\(', src[i:i + 20]):
        return False
    k = i
    for prefix in ("u8", "u", "U", "L"):
        if src[max(0, i - len(prefix)):i] == prefix:
            k = i - len(prefix)
            break
    return k == 0 or not (src[k - 1].isalnum() or src[k - 1] == "_")


def c_comments(src, js):
    """(line, text) of every // and /* */ comment, skipping string, char and raw-string literals."""
    out, i, n, line = [], 0, len(src), 1
    while i < n:
        ch = src[i]
        if ch == "\n":
            line += 1
            i += 1
        elif src.startswith("//", i):
            end = src.find("\n", i)
            end = n if end < 0 else end
            out.append((line, src[i + 2:end]))
            i = end
        elif src.startswith("/*", i):
            end = src.find("*/", i + 2)
            end = n if end < 0 else end
            for k, part in enumerate(src[i + 2:end].split("\n")):
                out.append((line + k, part))
            line += src.count("\n", i, end)
            i = end + 2
        elif not js and raw_string_at(src, i):
            m = re.match(r'R"([^()\\\s]{0,16})\(', src[i:])
            close = ")" + m.group(1) + '"'
            end = src.find(close, i + m.end())
            end = n if end < 0 else end + len(close)
            line += src.count("\n", i, end)
            i = end
        elif ch == '"' or ch == "'" or (js and ch == "`"):
            if ch == "'" and not js:
                # A digit separator (1'000, 0xFF'FF) is not a char literal.
                k = i
                while k > 0 and (src[k - 1].isalnum() or src[k - 1] == "_"):
                    k -= 1
                if k < i and src[k].isdigit():
                    i += 1
                    continue
            j = i + 1
            while j < n and src[j] != ch and (ch == "`" or src[j] != "\n"):
                j += 2 if src[j] == "\\" else 1
            line += src.count("\n", i, min(j, n))
            i = j + 1
        else:
            i += 1
    return out


def python_comments(src):
    try:
        return [(t.start[0], t.string[1:]) for t in tokenize.generate_tokens(io.StringIO(src).readline)
                if t.type == tokenize.COMMENT]
    except (tokenize.TokenError, IndentationError, SyntaxError):
        return hash_comments(src, "python")


def hash_comments(src, lang):
    """(line, text) of every # comment of a shell, CMake, Make or Python-like file, skipping quoted
    text, CMake bracket arguments, shell here-documents and parameter expansions."""
    out, i, n, line = [], 0, len(src), 1
    stack = []          # open contexts: '"', "'", '"""', "'''", '$(', '${'
    heredocs = []       # (delimiter, fed to Python) of the here-documents starting on the next line
    while i < n:
        ch = src[i]
        top = stack[-1] if stack else None
        if ch == "\n":
            line += 1
            i += 1
            if heredocs and top in (None, "$("):
                for delim, python in heredocs:
                    first, body = line, []
                    while i < n:
                        end = src.find("\n", i)
                        end = n if end < 0 else end
                        text = src[i:end]
                        i = end + 1
                        line += 1
                        if text.strip() == delim:
                            break
                        body.append(text)
                    if python:  # a script fed to Python: its comments are code comments
                        out += [(first + k - 1, t) for k, t in python_comments("\n".join(body) + "\n")]
                heredocs = []
            continue
        if top in ("'", "'''") and not (lang == "python" and ch == "\\"):
            if src.startswith(top, i):
                stack.pop()
                i += len(top)
            else:
                i += 1
            continue
        if ch == "\\":
            i += 2
            line += src.count("\n", i - 1, min(i, n))
            continue
        if top in ('"', '"""'):
            if src.startswith(top, i):
                stack.pop()
                i += len(top)
            elif lang == "shell" and src.startswith("$(", i):
                stack.append("$(")
                i += 2
            elif lang == "shell" and src.startswith("${", i):
                stack.append("${")
                i += 2
            else:
                i += 1
            continue
        # Code (top level, or inside a shell command substitution or parameter expansion).
        if ch == "#":
            prev = src[i - 1] if i > 0 else "\n"
            starts = True
            if lang == "shell":
                starts = prev in " \t\n;&|()" and top != "${"
            if lang == "cmake":
                m = re.match(r"#\[(=*)\[", src[i:])
                if m:
                    close = "]" + m.group(1) + "]"
                    end = src.find(close, i)
                    end = n if end < 0 else end
                    for k, part in enumerate(src[i + m.end():end].split("\n")):
                        out.append((line + k, part))
                    line += src.count("\n", i, end)
                    i = end + len(close)
                    continue
            if starts:
                end = src.find("\n", i)
                end = n if end < 0 else end
                if not (i == 0 and src.startswith("#!")):
                    out.append((line, src[i + 1:end]))
                i = end
                continue
            i += 1
            continue
        if lang == "python" and (src.startswith('"""', i) or src.startswith("'''", i)):
            stack.append(src[i:i + 3])
            i += 3
        elif ch in "\"'" and not (lang == "cmake" and ch == "'"):
            if lang == "shell" and ch == "'" and top == "${":
                i += 1
            else:
                stack.append(ch)
                i += 1
        elif lang == "cmake" and re.match(r"\[=*\[", src[i:]):
            m = re.match(r"\[(=*)\[", src[i:])
            close = "]" + m.group(1) + "]"
            end = src.find(close, i + m.end())
            end = n if end < 0 else end
            line += src.count("\n", i, end)
            i = end + len(close)
        elif lang == "shell" and src.startswith("<<", i) and not src.startswith("<<<", i):
            m = re.match(r"<<-?\s*(['\"]?)([A-Za-z_][A-Za-z0-9_]*)\1", src[i:])
            if m:
                # The command that reads the body, back through continued lines.
                start = i
                while True:
                    start = src.rfind("\n", 0, start)
                    if start <= 0 or src[start - 1] != "\\":
                        break
                command = src[start + 1:i]
                python = m.group(2) == "PY" or re.search(r"python|\$\{?PY\b", command) is not None
                heredocs.append((m.group(2), python))
                i += m.end()
            else:
                i += 2
        elif lang == "shell" and src.startswith("$(", i):
            stack.append("$(")
            i += 2
        elif lang == "shell" and src.startswith("${", i):
            stack.append("${")
            i += 2
        elif lang == "shell" and ch == "(" and top == "$(":
            stack.append("$(")
            i += 1
        elif lang == "shell" and ((ch == ")" and top == "$(") or (ch == "}" and top == "${")):
            stack.pop()
            i += 1
        else:
            i += 1
    return out


def language(path, src):
    name = path.rsplit("/", 1)[-1]
    if re.search(r"\.(cc|h|cpp|hpp|c)(\.in)?$", name):
        return "c"
    if name.endswith((".js", ".mjs")):
        return "js"
    if name.endswith(".py"):
        return "python"
    if name == "Snakefile" or name.endswith(".smk"):
        return "snakefile"
    if name.endswith(".cmake") or name == "CMakeLists.txt":
        return "cmake"
    if name.endswith(".sh") or name == "Makefile":
        return "shell"
    first = src.split("\n", 1)[0]
    if first.startswith("#!"):
        return "python" if "python" in first else "shell"
    return None


def comments(path, src):
    lang = language(path, src)
    if lang in ("c", "js"):
        return c_comments(src, lang == "js")
    if lang == "python":
        return python_comments(src)
    if lang == "snakefile":
        return hash_comments(src, "python")
    if lang in ("cmake", "shell"):
        return hash_comments(src, lang)
    return []


def main():
    paths = [p for p in sys.stdin.read().split("\0") if p]
    hits = []
    for path in paths:
        try:
            with open(path, encoding="utf-8", errors="replace") as f:
                src = f.read()
        except OSError:
            continue
        for line, text in comments(path, src):
            if offends(text):
                hits.append("%s:%d: %s" % (path, line, text.strip()))
    for hit in hits:
        print(hit)
    return 1 if hits else 0


sys.exit(main())
PY

# Self-check: the scanner must flag a dated comment and an issue number, and pass directives,
# shebangs, colours and dates that live in string literals.
mkdir -p "$work/sample"
cat > "$work/sample/dated.cc" <<'EOF'
int batch = 4;  // batched until @DATE@
EOF
cat > "$work/sample/issue.cc" <<'EOF'
/* the reader skips the header
   (@ISSUE@ 67) */
int skip = 1;
EOF
cat > "$work/sample/issue.sh" <<'EOF'
#!/usr/bin/env bash
echo ok  # see @HASH@12
EOF
cat > "$work/sample/heredoc.sh" <<'EOF'
/usr/bin/python3 - "$1" <<'PYEOF'
import sys
# the file of @ISSUE@ 3
print(sys.argv[1])
PYEOF
EOF
cat > "$work/sample/month.py" <<'EOF'
x = 3  # measured in @MONTH@ on 2 cores
EOF
cat > "$work/sample/session.cmake" <<'EOF'
# kept from this session
set(X 1)
EOF
cat > "$work/sample/clean.cc" <<'EOF'
#include <x>
#pragma once
#define STAMP "@DATE@"
const char* when = "@DATE@ // @ISSUE@ 67";
const char* raw = R"(/* @HASH@12 */)";
int big = 1'000'000; const char* after = "@ISSUE@ 67";  // digit separators open no char literal
char c = '"';  // the colour #ff00aa is no issue number
EOF
cat > "$work/sample/clean.sh" <<'EOF'
#!/usr/bin/env bash
# Prints the stamp of the run.
echo "built @DATE@ # @ISSUE@ 4" '@HASH@12'
n=${#list[@]}; echo "$# $(echo "a # @ISSUE@ 5")"
cat <<TXT
# @ISSUE@ 6 is data in a here-document
TXT
EOF
cat > "$work/sample/clean.py" <<'EOF'
#!/usr/bin/env python3
s = "# @ISSUE@ 7, @DATE@"  # the stamp format a reader parses
doc = """
# @ISSUE@ 8
"""
EOF
cat > "$work/sample/clean.cmake" <<'EOF'
set(S "@DATE@ # @ISSUE@ 9")  # a version stamp the build prints
EOF
# The samples spell their dates and issue numbers as placeholders, so that no scan of this file
# reads them as its own comments; they become the real thing here.
for f in "$work"/sample/*; do
  sed -i "s/@DATE@/$(printf '%s-%s-%s' 2026 11 29)/g; s/@MONTH@/Nov $(printf '%s' 2026)/g; s/@ISSUE@/issue/g; s/@HASH@/#/g" "$f"
done
fail=0
for f in dated.cc issue.cc issue.sh heredoc.sh month.py session.cmake; do
  if (cd "$work/sample" && printf '%s\0' "$f" | "$python" "$work/scan.py" > /dev/null); then
    echo "self-check: the scanner did not flag $f"; fail=1
  fi
done
for f in clean.cc clean.sh clean.py clean.cmake; do
  if ! out=$(cd "$work/sample" && printf '%s\0' "$f" | "$python" "$work/scan.py"); then
    echo "self-check: the scanner flagged a clean sample:"; echo "$out"; fail=1
  fi
done
[ $fail = 0 ] || exit 1

# The code files of the repository: tracked and untracked-but-not-ignored ones in a git checkout.
if git -C . rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -d '' -t files < <(git -C . ls-files -z --cached --others --exclude-standard)
else
  mapfile -d '' -t files < <(find . -type f -not -path './build*' -not -path './.git/*' -printf '%P\0')
fi
code=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  case "$f" in tests/data/*|"$self") continue ;; esac
  case "$f" in
    *.cc|*.h|*.cc.in|*.h.in|*.cmake|CMakeLists.txt|*/CMakeLists.txt|*.py|*.sh|*.js|*.mjs|Snakefile|*/Snakefile|*.smk|Makefile|*/Makefile|.ci/*)
      code+=("$f") ;;
  esac
done
if ! out=$(printf '%s\0' "${code[@]}" | "$python" "$work/scan.py"); then
  echo "comments that carry a date, an issue number or a session's history (say why instead):"
  echo "$out"
  exit 1
fi
echo "checked the comments of ${#code[@]} code files: none carries a date, an issue number or a session's history"
