"""The commands in README.md and docs/*.md against the tool and the tree (issue 25).

Every shell line in a ```bash / ```sh block that runs `scatterlab` (build/bin/scatterlab or an
installed one) must name a command the tool has and only options that command (or the global
ones) takes, as its --help lists them; every repository path a line names (data/..., scripts/...,
tests/...) must exist (the real data ships in data/vdb and data/meshes); a Python line that imports
scatterlab must name the interpreter the build chose. A check, not a run: the long commands
(experiments of hours, benchmarks) are not executed; the quick ones are run by tests/python and
tests/consumer. Exit 0 when every line passes, 1 with one message per failing line.

    check_doc_commands.py --scatterlab build/bin/scatterlab --source . --python /usr/bin/python3
"""
import argparse
import glob
import os
import re
import shlex
import subprocess
import sys


def shell_lines(text):
    """(line number, command) of each shell line in ```bash / ```sh blocks, continuations
    joined, comments and blank lines dropped."""
    out, fence, buf, start = [], None, "", 0
    for n, line in enumerate(text.split("\n"), 1):
        stripped = line.strip()
        if stripped.startswith("```"):
            fence = None if fence is not None else stripped[3:].strip()
            continue
        if fence not in ("bash", "sh", "shell", "console"):
            continue
        if not buf:
            start = n
        if stripped.endswith("\\"):
            buf += stripped[:-1] + " "
            continue
        buf += stripped
        if buf and not buf.startswith("#"):
            out.append((start, buf))
        buf = ""
    return out


def help_options(cli, args):
    """The long and short option names --help lists for `scatterlab ARGS`, and the subcommands."""
    text = subprocess.run([cli] + args + ["--help"], capture_output=True, text=True).stdout
    options = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", text.split("Options:", 1)[-1]))
    subs = set()
    if "Subcommands:" in text:
        for line in text.split("Subcommands:", 1)[1].split("\n"):
            m = re.match(r"\s{2}(\w[\w-]*)\s", line)
            if m:
                subs.add(m.group(1))
    return options, subs


def segments(line):
    """The simple commands of a line (split at ;, &&, ||, |, and a for loop's do/done)."""
    try:
        words = shlex.split(line, comments=True)
    except ValueError:
        return [line.split()]
    seg, out = [], []
    for w in words:
        if w in (";", "&&", "||", "|", "&", "do", "done") or w.endswith(";"):
            if w.endswith(";") and w != ";":
                seg.append(w[:-1])
            out.append(seg)
            seg = []
        else:
            seg.append(w)
    out.append(seg)
    return [s for s in out if s]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scatterlab", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--python", required=True, help="the interpreter the build chose")
    a = ap.parse_args()
    root = os.path.abspath(a.source)
    top, commands = help_options(a.scatterlab, [])
    known = {c: help_options(a.scatterlab, [c]) for c in commands}
    for c, (opts, subs) in list(known.items()):
        for s in subs:
            known[c + " " + s] = help_options(a.scatterlab, [c, s])
    files = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    failures, checked = [], 0
    for path in files:
        rel = os.path.relpath(path, root)
        with open(path, encoding="utf-8") as f:
            lines = shell_lines(f.read())
        for n, line in lines:
            where = "%s:%d: %s" % (rel, n, line)
            if "import scatterlab" in line and not re.search(r"(^|\s)%s\s" % re.escape(a.python), line):
                failures.append("%s\n    imports scatterlab without naming %s" % (where, a.python))
            for words in segments(line):
                # Repository paths (not outputs under out/).
                for w in words:
                    for p in re.findall(r"(?:^|=)((?:data|scripts|tests|docs|cmake|experiment)/[\w./-]+)", w):
                        if "$" in p or "*" in p:
                            continue
                        if not os.path.exists(os.path.join(root, p)):
                            failures.append("%s\n    names %s, which does not exist" % (where, p))
                while words and re.match(r"^\w+=", words[0]):
                    words = words[1:]  # environment assignments
                if not words or os.path.basename(words[0]) != "scatterlab":
                    continue
                checked += 1
                args = words[1:]
                opts, cmd = set(top), None
                i = 0
                while i < len(args):
                    w = args[i]
                    if not w.startswith("-") and cmd is None:
                        if w not in known:
                            failures.append("%s\n    '%s' is not a scatterlab command" % (where, w))
                            break
                        cmd = w
                        if i + 1 < len(args) and (cmd + " " + args[i + 1]) in known:
                            cmd = cmd + " " + args[i + 1]
                            i += 1
                        opts = set(top) | known[cmd][0]
                    elif w.startswith("-") and not re.match(r"^-?\d", w[1:]):
                        name = w.split("=", 1)[0]
                        if name not in opts:
                            failures.append("%s\n    '%s' is not an option of scatterlab %s"
                                            % (where, name, cmd or ""))
                    i += 1
    for f in failures:
        print(f)
    print("%d scatterlab command lines checked in %d files, %d problem(s)"
          % (checked, len(files), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
