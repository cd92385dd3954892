#!/usr/bin/env python3
"""The commands and options the README and docs/ name exist.

Every `mrcheck CMD ... --flag` written in README.md and docs/*.md (up to the
end of its code span) is checked against `mrcheck CMD --help`: an unknown
command or an option the command does not list is one line and exit 1, so
a renamed option (--ghost-t became --ghost-opacity) cannot stay in the docs.

Usage: check_doc_options.py SOURCE_DIR MRCHECK [--pending CMD,CMD]
(--pending: commands being built elsewhere, not yet on this branch).
"""
import glob
import os
import re
import subprocess
import sys

SUBS = {"bench": ["frame", "ao", "shadows", "ghost", "multiview", "tracking", "map", "measure", "scene", "load"],
        "study": ["stimuli", "plan", "run", "analyze"], "hall": ["init", "add", "show"], "bcf": ["list"]}


def main():
    src, mr = sys.argv[1], sys.argv[2]
    pending = set(sys.argv[4].split(",")) if len(sys.argv) > 4 and sys.argv[3] == "--pending" else set()
    top = subprocess.run([mr, "--help"], capture_output=True, text=True).stdout
    commands = set(re.findall(r"^  (\w+) ", top, re.M))
    if len(commands) < 10:
        print("check_doc_options: mrcheck --help lists %d commands" % len(commands))
        return 1
    helps, bad, seen = {}, 0, 0
    files = [os.path.join(src, "README.md")] + sorted(glob.glob(os.path.join(src, "docs", "*.md")))
    for f in files:
        for ln, line in enumerate(open(f, encoding="utf-8"), 1):
            for m in re.finditer(r"mrcheck (\w+)((?: [\w.|\\]+)?)([^`\n]*)", line):
                cmd, rest = m.group(1), m.group(2).strip()
                if cmd in pending:
                    continue
                if cmd not in commands:
                    # Prose ("mrcheck is ...", "mrcheck's") is not a command line.
                    if "`mrcheck " + cmd in line or "./build/mrcheck " + cmd in line:
                        print("%s:%d: no command 'mrcheck %s'" % (os.path.relpath(f, src), ln, cmd))
                        bad += 1
                    continue
                key = cmd + " " + rest if cmd in SUBS and rest in SUBS[cmd] else cmd
                if key not in helps:
                    r = subprocess.run([mr] + key.split() + ["--help"], capture_output=True, text=True)
                    helps[key] = r.stdout + r.stderr
                span = re.split(r"\| `mrcheck|`\s*\|", m.group(3))[0]
                for flag in re.findall(r"--([a-z][a-z0-9-]*)", span):
                    seen += 1
                    if flag != "help" and not re.search(r"--" + re.escape(flag) + r"(?![a-z0-9-])", helps[key]):
                        print("%s:%d: mrcheck %s: --%s is not in its --help" % (os.path.relpath(f, src), ln, key, flag))
                        bad += 1
    print("check_doc_options: %d options in %d files checked, %d wrong" % (seen, len(files), bad))
    return 1 if bad or seen < 50 else 0


if __name__ == "__main__":
    sys.exit(main())
