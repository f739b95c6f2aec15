#!/usr/bin/env python3
"""Prints the translation units of src/ and tools/ that scripts/tidy.sh --since REV must check.

A unit differs from REV when its source changed, or when a header it includes (directly or not,
the project's own; found by the compiler's -MM) changed, in the commits since REV or in the work
tree. Every unit is printed when .clang-tidy, a CMakeLists.txt or cmake/ changed (the checks or the
flags), or when REV is not an ancestor of HEAD. One line per unit: a regular expression matching
its path exactly, as run-clang-tidy takes them.
"""
import argparse
import concurrent.futures
import json
import os
import re
import shlex
import subprocess
import sys


def git(*args):
    return subprocess.run(["git", *args], check=True, capture_output=True, text=True).stdout


def changed_files(since):
    """Absolute real paths of the files changed since `since`, committed or not, and new ones."""
    names = set(git("diff", "--name-only", since).split())
    names |= set(git("ls-files", "--others", "--exclude-standard").split())
    top = git("rev-parse", "--show-toplevel").strip()
    return {os.path.realpath(os.path.join(top, n)) for n in names}, top


def every_unit_changes(path, top):
    """The checks, or the flags of src/ and tools/ (tests/, bench/ and fuzz/ have their own)."""
    rel = os.path.relpath(path, top)
    if rel in (".clang-tidy", "CMakeLists.txt") or rel.startswith("cmake/"):
        return True
    return os.path.basename(rel) == "CMakeLists.txt" and rel.startswith(("src/", "tools/"))


def project_headers(entry):
    """The project headers a unit includes, by the compiler's -MM (system headers left out)."""
    args = shlex.split(entry["command"]) if "command" in entry else list(entry["arguments"])
    if os.path.basename(args[0]) == "ccache":
        args = args[1:]
    out = []
    skip = False
    for a in args[1:]:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a == "-c" or a.startswith("-Winvalid-pch"):
            continue
        out.append(a)
    # -MG: a header generated at build time (the dds area's idlc output) need not exist yet.
    cmd = [args[0], *out, "-MM", "-MG"]
    result = subprocess.run(cmd, cwd=entry["directory"], capture_output=True, text=True)
    if result.returncode != 0:
        return None  # cannot tell: the unit is checked
    deps = result.stdout.replace("\\\n", " ").split(":", 1)[-1].split()
    return {os.path.realpath(os.path.join(entry["directory"], d)) for d in deps}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", required=True, help="the build tree with compile_commands.json")
    parser.add_argument("--since", required=True, help="the commit whose tree was clean")
    parser.add_argument("--explain", action="store_true", help="say on stderr why each unit is checked")
    options = parser.parse_args()

    entries = json.load(open(os.path.join(options.build, "compile_commands.json")))
    top = git("rev-parse", "--show-toplevel").strip()
    roots = (os.path.join(top, "src") + os.sep, os.path.join(top, "tools") + os.sep)
    entries = [e for e in entries if os.path.realpath(e["file"]).startswith(roots)]

    def emit(units):
        for f in sorted(units):
            print("^" + re.escape(f) + "$")

    ancestor = subprocess.run(["git", "merge-base", "--is-ancestor", options.since, "HEAD"],
                              capture_output=True).returncode == 0
    if not ancestor:
        print(f"tidy_units: {options.since} is not an ancestor of HEAD: every unit", file=sys.stderr)
        emit({e["file"] for e in entries})
        return
    changed, top = changed_files(options.since)
    if any(every_unit_changes(p, top) for p in changed):
        print("tidy_units: the checks or the build flags changed: every unit", file=sys.stderr)
        emit({e["file"] for e in entries})
        return
    units = {e["file"] for e in entries if os.path.realpath(e["file"]) in changed}
    headers = {p for p in changed if p.endswith((".hpp", ".h", ".hxx", ".ipp", ".inc", ".idl"))}
    rest = [e for e in entries if e["file"] not in units]
    if headers and rest:
        with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
            for entry, deps in zip(rest, pool.map(project_headers, rest)):
                if deps is None or deps & headers:
                    units.add(entry["file"])
    emit(units)


if __name__ == "__main__":
    main()
