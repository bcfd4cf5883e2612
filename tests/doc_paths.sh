#!/usr/bin/env bash
# Every repository path that the docs (docs/*.md, README.md) or a source comment
# (src, include, cli, tests, bench, fuzz, scripts) names must exist, so that a moved or
# deleted file leaves no stale reference behind: paths under src, include, tests, bench,
# scripts, scenes, examples, cli and fuzz, and C files named from inside src or include
# (kernel/kernel.h, woven/fit.h). Placeholders (src/<concept>/, examples/P.json) are skipped,
# globs must match something. Prints each missing path with where it is named and fails if
# there is any. Usage: doc_paths.sh [WOVEN] SOURCE_DIR (WOVEN is accepted and ignored, so
# the test is called like the CLI tests).
set -u
SRC=${!#}
cd "$SRC" || { echo "FAIL no source directory $SRC"; exit 1; }

# The tree: git's files (tracked and untracked, not ignored) when this is a checkout, else find.
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  list() { git ls-files --cached --others --exclude-standard; }
else
  list() { find . \( -name .git -o -name 'build*' -o -name node_modules \) -prune -o -type f -print | sed 's|^\./||'; }
fi

list | python3 -c '
import fnmatch, os, re, sys

files = [f for f in sys.stdin.read().splitlines() if os.path.exists(f)]
tree = set(files)
for f in files:                       # every directory above a file
    parts = f.split("/")
    for i in range(1, len(parts)):
        tree.add("/".join(parts[:i]))

ROOTS = "src|include|cli|tests|bench|fuzz|scripts|scenes|examples"
# A path starts a word (not inside another path such as build/tests/..., ../examples/...).
PATH = re.compile(r"(?<![\w./\-])(?:%s)(?:/[\w.\-{},<>*]*)*" % ROOTS)
# A source file named from inside src/ or include/ (kernel/kernel.h, woven/fit.h).
INNER = re.compile(r"(?<![\w./\-<])(?!(?:%s)/)[A-Za-z_]\w*/[\w\-]+\.(?:c|h|inc)\b(?![\w/])" % ROOTS)
C_LIKE = (".c", ".h", ".inc", ".mjs", ".js")
HASH = (".sh", ".bash", ".py", ".cmake", ".supp", ".dict", "CMakeLists.txt")

def c_comments(text):
    """Comments of C and JavaScript text; string and character literals skipped."""
    out = []
    for m in re.finditer(r"\"(?:\\.|[^\"\\\n])*\"|\x27(?:\\.|[^\x27\\\n])*\x27|/\*.*?\*/|//[^\n]*", text, re.S):
        s = m.group(0)
        if s.startswith("/"):
            out.append((text.count("\n", 0, m.start()) + 1, s))
    return out

def hash_comments(text):
    """Text after a # that starts a comment (line start or after a blank), outside quotes."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if line.startswith("#!"):
            continue
        q = None
        for i, ch in enumerate(line):
            if q:
                if ch == q: q = None
            elif ch in "\"\x27":
                q = ch
            elif ch == "#" and (i == 0 or line[i - 1] in " \t"):
                out.append((n, line[i:]))
                break
    return out

def sources():
    for f in files:
        if f.startswith("docs/") and f.endswith(".md") or f == "README.md":
            yield f, [(1, open(f, encoding="utf-8", errors="replace").read())]
        elif f.split("/")[0] in ("src", "include", "cli", "tests", "bench", "fuzz", "scripts"):
            if f.endswith(C_LIKE):
                yield f, c_comments(open(f, encoding="utf-8", errors="replace").read())
            elif f.endswith(HASH):
                yield f, hash_comments(open(f, encoding="utf-8", errors="replace").read())

def expand(p):
    """a/{b,c}.h -> a/b.h, a/c.h"""
    m = re.search(r"\{([^{}]*)\}", p)
    if not m:
        return [p]
    return [q for alt in m.group(1).split(",") for q in expand(p[:m.start()] + alt + p[m.end():])]

def placeholder(p):
    # src/<concept>/, src/..., examples/P.json, NAME.json: stand for some path
    if "<" in p or ">" in p or "..." in p:
        return True
    return any(re.fullmatch(r"[A-Z][A-Z0-9_]*", c.split(".")[0]) for c in p.split("/")[1:] if c)

def exists(p):
    p = p.rstrip("/")
    if "*" in p:
        return any(fnmatch.fnmatchcase(t, p) for t in tree)
    return p in tree

missing = {}
for f, chunks in sources():
    for line0, chunk in chunks:
        for m in PATH.finditer(chunk):
            raw = m.group(0).rstrip(".,")
            if "/" not in raw or placeholder(raw):
                continue
            line = line0 + chunk.count("\n", 0, m.start())
            for p in expand(raw):
                if not exists(p) and not exists(p + ".c"):     # bench/recover: the program of bench/recover.c
                    missing.setdefault(p, []).append("%s:%d" % (f, line))
        for m in INNER.finditer(chunk):
            p = m.group(0)
            if not any(exists(q) for q in ("src/" + p, "include/" + p, os.path.join(os.path.dirname(f), p))):
                missing.setdefault(p, []).append("%s:%d" % (f, line0 + chunk.count("\n", 0, m.start())))

for p in sorted(missing):
    print("FAIL %s does not exist; named in %s" % (p, ", ".join(missing[p])))
print("%d missing path(s)" % len(missing))
sys.exit(1 if missing else 0)
'
