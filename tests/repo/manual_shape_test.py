"""The shape of the house: docs read as a manual, the run of a method reads as a list of stages.

- every manual page (docs/*.md) is at most MAX_PAGE_LINES lines, and docs/README.md links it;
- every record file (docs/record/*.md) is linked from docs/record/README.md;
- every relative markdown link in docs/, README.md and benchmarks/ names a file that exists;
- no function in the file that composes a method's stages is longer than MAX_STAGE_LINES lines.
Usage: manual_shape_test.py REPO_ROOT [STAGES_FILE]. Exit 1 listing every breach.
"""
import os
import re
import sys

MAX_PAGE_LINES = 300   # a page a newcomer reads in one sitting
MAX_STAGE_LINES = 40   # a stage that fits on a screen

root = sys.argv[1]
stages_file = sys.argv[2] if len(sys.argv) > 2 else "methods/reconstruct.cc"
errors = []


def rel(p):
    return os.path.relpath(p, root)


def links(path):
    text = open(path, encoding="utf-8").read()
    text = re.sub(r"```.*?```", "", text, flags=re.S)  # code blocks hold commands, not links
    for m in re.finditer(r"\]\(([^)\s]+)\)", text):
        target = m.group(1).split("#")[0]
        if target and not re.match(r"[a-z]+:", target):
            yield target


docs = os.path.join(root, "docs")
pages = sorted(f for f in os.listdir(docs) if f.endswith(".md"))
index = set(os.path.normpath(t) for t in links(os.path.join(docs, "README.md")))
for page in pages:
    path = os.path.join(docs, page)
    n = sum(1 for _ in open(path, encoding="utf-8"))
    if n > MAX_PAGE_LINES:
        errors.append(f"{rel(path)}: {n} lines, a manual page has at most {MAX_PAGE_LINES}")
    if page != "README.md" and page not in index:
        errors.append(f"docs/README.md does not link {page}")
record = os.path.join(docs, "record")
if os.path.isdir(record):
    rindex = set(os.path.normpath(t) for t in links(os.path.join(record, "README.md")))
    for f in sorted(os.listdir(record)):
        if f.endswith(".md") and f != "README.md" and f not in rindex:
            errors.append(f"docs/record/README.md does not link {f}")

md_files = [os.path.join(root, "README.md")]
for d in ("docs", "benchmarks"):
    for dirpath, _, files in os.walk(os.path.join(root, d)):
        md_files += [os.path.join(dirpath, f) for f in files if f.endswith(".md")]
for path in md_files:
    for target in links(path):
        if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(path), target))):
            errors.append(f"{rel(path)}: broken link {target}")

# Functions of the stages file: a definition starts at column 0 (or two spaces inside a class), its
# signature may span lines up to the one ending in "{", and it ends at the brace at its indentation.
lines = open(os.path.join(root, stages_file), encoding="utf-8").read().split("\n")
start = candidate = None
for i, line in enumerate(lines):
    if start is None:
        if candidate is None and re.match(r"^(  )?[A-Za-z_].*\(", line) and \
                not re.match(r"^\s*(if|for|while|switch|return|namespace|struct|class|using)\b", line):
            candidate, indent = i, len(line) - len(line.lstrip())
        if candidate is not None:
            if line.rstrip().endswith("{"):
                start, candidate = candidate, None
            elif line.rstrip().endswith(";") or line.rstrip().endswith("}"):
                candidate = None
    elif line == " " * indent + "}":
        if i - start + 1 > MAX_STAGE_LINES:
            errors.append(f"{stages_file}:{start + 1}: {lines[start].strip()[:60]} is {i - start + 1} lines, "
                          f"a stage has at most {MAX_STAGE_LINES}")
        start = None

for e in errors:
    print(e)
print(f"checked {len(pages)} manual pages, {len(md_files)} markdown files, {stages_file}: "
      f"{'ok' if not errors else str(len(errors)) + ' problems'}")
sys.exit(1 if errors else 0)
