"""The commands in README.md and docs/*.md against the tool and the tree (issue 25).

Every shell line in a ```bash / ```sh block that runs `scatterlab` (build/bin/scatterlab or an
installed one) must name a command the tool has and only options that command (or the global
ones) takes, as its --help lists them; every repository path a line names (data/..., scripts/...,
tests/...) must exist (the real data ships in data/vdb and data/meshes); a Python line that imports
scatterlab must name the interpreter the build chose. The long commands (experiments of hours,
benchmarks) are only checked; with --run SECONDS every short block is also run as written, in a
fresh directory: a block whose commands are all `build/bin/scatterlab` render, compare, convert
or info, with no shell variables, animation or GPU, and whose inputs are repository files or
outputs of its own earlier commands (runnable()); one that fails or takes longer than SECONDS is
a problem. The Python lines are run by tests/python and tests/consumer. Exit 0 when every line
passes, 1 with one message per failing line.

    check_doc_commands.py --scatterlab build/bin/scatterlab --source . --python /usr/bin/python3 --run 120
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


def shell_blocks(text):
    """(first line number, [commands]) of each ```bash / ```sh block (shell_lines per block)."""
    blocks, fence, lines, start = [], None, [], 0
    for n, line in enumerate(text.split("\n"), 1):
        stripped = line.strip()
        if stripped.startswith("```"):
            if fence is None:
                fence, lines, start = stripped[3:].strip(), [], n
            else:
                if fence in ("bash", "sh", "shell", "console"):
                    blocks.append((start, [c for _, c in shell_lines("```sh\n" + "\n".join(lines) + "\n```")]))
                fence = None
            continue
        if fence is not None:
            lines.append(line)
    return blocks


# The commands a "short" block may hold: everything they read is in the repository or written by
# an earlier command of the same block, and they run in seconds on the shipped scenes.
RUNNABLE = ("render", "compare", "convert", "info")
INPUT_SUFFIXES = (".exr", ".png", ".json", ".vdb", ".sog")


def runnable(block, root):
    """The block's commands as argument lists when the whole block can run on its own, else None:
    only `build/bin/scatterlab` RUNNABLE commands, no shell variables, no animation (--frames) or
    GPU, every input either a repository file or an output of an earlier command."""
    made, out = set(), []
    for line in block:
        if "$" in line or "--frames" in line or "--gpu" in line:
            return None
        segs = segments(line)
        if len(segs) != 1:
            return None
        words = segs[0]
        if any(w == "--backend" and nxt == "gpu" for w, nxt in zip(words, words[1:])):
            return None
        if len(words) < 2 or words[0] != "build/bin/scatterlab" or words[1] not in RUNNABLE:
            return None
        outputs = {words[i + 1] for i, w in enumerate(words[:-1])
                   if w in ("-o", "--output", "--stats", "--png", "--diff", "--samples-png")}
        if words[1] == "convert" and len(words) > 3:
            outputs.add(words[3])  # convert IN OUT
        for i, w in enumerate(words[2:], 2):
            prev = words[i - 1]
            if w.startswith("-") or w in outputs or (prev.startswith("-") and prev not in ("--scene",)):
                continue
            if w.endswith(INPUT_SUFFIXES) and w not in made and not os.path.exists(os.path.join(root, w)):
                return None
        made |= outputs
        out.append(words)
    return out or None


def run_block(cli, root, commands, timeout):
    """Runs a block's commands in a fresh directory (repository paths made absolute); returns the
    failure message or None, and the seconds it took."""
    import tempfile
    import time
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="scatterlab-doc-") as d:
        for words in commands:
            args = [cli] + [os.path.join(root, w) if re.match(r"^(data|docs|scripts)/", w) else w
                            for w in words[1:]]
            left = timeout - (time.time() - t0)
            try:
                r = subprocess.run(args, cwd=d, capture_output=True, text=True,
                                   timeout=max(left, 1))
            except subprocess.TimeoutExpired:
                return "took more than %d s (a short block should take seconds)" % timeout, timeout
            if r.returncode != 0:
                return ("'%s' exited %d: %s" % (" ".join(words), r.returncode,
                                                 (r.stderr or r.stdout).strip()[-400:]),
                        time.time() - t0)
    return None, time.time() - t0


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
    ap.add_argument("--run", type=int, default=0, metavar="SECONDS",
                    help="also run every short block (runnable()), each within SECONDS")
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
    ran = 0
    if a.run > 0:
        for path in files:
            rel = os.path.relpath(path, root)
            with open(path, encoding="utf-8") as f:
                blocks = shell_blocks(f.read())
            for start, block in blocks:
                commands = runnable(block, root)
                if not commands:
                    continue
                ran += 1
                problem, seconds = run_block(os.path.abspath(a.scatterlab), root, commands, a.run)
                print("ran %s:%d (%d commands) in %.1f s" % (rel, start, len(commands), seconds))
                if problem:
                    failures.append("%s:%d: the block\n    %s" % (rel, start, problem))
    for f in failures:
        print(f)
    print("%d scatterlab command lines checked in %d files, %d short blocks run, %d problem(s)"
          % (checked, len(files), ran, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
