#!/usr/bin/env python3
"""Runs the example commands of README.md and docs/*.md against a built knitsim (ctest
docs_examples), so that a renamed flag or file breaks the build, not the reader.

    docs/run_examples.py KNITSIM              run every runnable block
    docs/run_examples.py KNITSIM --self-test  a block with an unknown flag must fail
                                              (ctest docs_examples_catches)

A runnable block is a fenced block whose opening line is exactly

    ```sh runnable

(GitHub still highlights it as sh). Only quick commands (seconds) belong in one; other
examples use a plain ```sh block. Each block runs with `bash -e -o pipefail` in a fresh temporary
folder holding `build/knitsim` (the binary under test; `knitsim` is on PATH too) and links to the
source tree's `docs/`, `models/`, `paper_repro/` and `experiments/`, so commands are written as a
user types them in a checkout after the build. A block fails if any command in it exits non-zero
(write `cmd || test $? = 3` for a command whose documented exit status is 3) or runs over 300 s.
Standard library only.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OPEN = "```sh runnable"
LINKED = ["docs", "models", "paper_repro", "experiments"]


def blocks(path):
    """(line number, text) of each runnable block of the Markdown file `path`."""
    found, current, start = [], None, 0
    with open(path) as f:
        for number, line in enumerate(f, 1):
            stripped = line.rstrip("\n")
            if current is None and stripped.strip() == OPEN:
                current, start = [], number
            elif current is not None and stripped.strip() == "```":
                found.append((start, "".join(current)))
                current = None
            elif current is not None:
                current.append(line)
    if current is not None:
        sys.exit("%s:%d: runnable block not closed" % (path, start))
    return found


def documents():
    files = [os.path.join(ROOT, "README.md")]
    files += sorted(os.path.join(HERE, n) for n in os.listdir(HERE) if n.endswith(".md"))
    return files


def run_block(knitsim, text):
    """Exit status and output of `text` run in a fresh folder."""
    work = tempfile.mkdtemp(prefix="knitsim-example-")
    try:
        os.makedirs(os.path.join(work, "build"))
        os.symlink(knitsim, os.path.join(work, "build", "knitsim"))
        for name in LINKED:
            os.symlink(os.path.join(ROOT, name), os.path.join(work, name))
        env = dict(os.environ)
        env["PATH"] = os.path.join(work, "build") + os.pathsep + env.get("PATH", "")
        try:
            done = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", text], cwd=work, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=300)
            return done.returncode, done.stdout
        except subprocess.TimeoutExpired as e:
            return -1, (e.stdout or "") + "\n(over 300 s)"
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 1:
        sys.exit(__doc__)
    knitsim = os.path.abspath(args[0])
    if "--self-test" in sys.argv:
        status, _ = run_block(knitsim, "build/knitsim drape --a-renamed-flag 1 --quiet\n")
        if status == 0:
            sys.exit("docs_examples_catches: a block with an unknown flag passed")
        print("docs_examples_catches: a block with an unknown flag fails (exit %d)" % status)
        return
    failed, count = [], 0
    for path in documents():
        for line, text in blocks(path):
            count += 1
            where = "%s:%d" % (os.path.relpath(path, ROOT), line)
            status, output = run_block(knitsim, text)
            print("%s: %s" % (where, "ok" if status == 0 else "FAILED (exit %d)" % status))
            if status != 0:
                failed.append(where)
                print(re.sub(r"(?m)^", "    ", output.rstrip()))
    if count == 0:
        sys.exit("no runnable blocks found (```sh runnable) in README.md and docs/*.md")
    if failed:
        sys.exit("%d of %d runnable blocks failed: %s" % (len(failed), count, ", ".join(failed)))
    print("%d runnable blocks ran" % count)


if __name__ == "__main__":
    main()
