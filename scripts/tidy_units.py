#!/usr/bin/env python3
"""Prints the translation units of src/ and tools/ that scripts/tidy.sh --since REV must check.

A unit differs from REV when its source changed, or when a header it includes (directly or not,
the project's own; found by the compiler's -MM) changed, in the commits since REV or in the work
tree, or when its compile command differs from the one recorded in .ci/tidy-flags.json (written by
`tidy_units.py --record` after the whole-tree run that found REV clean): a CMakeLists.txt change
then costs only the units whose flags it changed. Every unit is printed when .clang-tidy or cmake/
changed, when a CMakeLists.txt changed and no record of REV's flags exists, or when REV is not an
ancestor of HEAD. One line per unit: a regular expression matching its path exactly, as
run-clang-tidy takes them.
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


FLAGS_RECORD = ".ci/tidy-flags.json"


def every_unit_changes(path, top, flags_known):
    """The checks, or the flags of src/ and tools/ (tests/, bench/ and fuzz/ have their own) when
    no record of the clean commit's flags says which units a CMakeLists.txt change reached."""
    rel = os.path.relpath(path, top)
    if rel == ".clang-tidy" or rel.startswith("cmake/"):
        return True
    if flags_known:
        return False
    if rel == "CMakeLists.txt":
        return True
    return os.path.basename(rel) == "CMakeLists.txt" and rel.startswith(("src/", "tools/"))


def normalised_command(entry, top):
    """A unit's compile command without its own file names, with the tree's and the build tree's
    paths replaced, so that two clones of one commit give the same text."""
    args = shlex.split(entry["command"]) if "command" in entry else list(entry["arguments"])
    if os.path.basename(args[0]) == "ccache":
        args = args[1:]
    out = []
    skip = False
    for a in args[1:]:
        if skip:
            skip = False
            continue
        if a in ("-o", "-c"):
            skip = a == "-o"
            continue
        if os.path.realpath(os.path.join(entry["directory"], a)) == os.path.realpath(entry["file"]):
            continue
        out.append(a)
    text = " ".join([os.path.basename(args[0]), *out])
    build = os.path.realpath(entry["directory"])
    return text.replace(build, "@BUILD@").replace(os.path.realpath(top), "@ROOT@")


def unit_key(entry, top):
    return os.path.relpath(os.path.realpath(entry["file"]), os.path.realpath(top))


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
    parser.add_argument("--record", action="store_true",
                        help=f"write every unit's compile command to {FLAGS_RECORD} (after a whole clean run)")
    options = parser.parse_args()

    entries = json.load(open(os.path.join(options.build, "compile_commands.json")))
    top = git("rev-parse", "--show-toplevel").strip()
    roots = (os.path.join(top, "src") + os.sep, os.path.join(top, "tools") + os.sep)
    entries = [e for e in entries if os.path.realpath(e["file"]).startswith(roots)]
    record_path = os.path.join(top, FLAGS_RECORD)
    if options.record:
        record = {"commit": git("rev-parse", "HEAD").strip(),
                  "units": {unit_key(e, top): normalised_command(e, top) for e in entries}}
        with open(record_path, "w") as f:
            json.dump(record, f, indent=0, sort_keys=True)
            f.write("\n")
        print(f"tidy_units: {len(entries)} compile commands recorded in {FLAGS_RECORD}", file=sys.stderr)
        return

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
    recorded = None
    if os.path.exists(record_path):
        record = json.load(open(record_path))
        if record.get("commit") == git("rev-parse", options.since).strip():
            recorded = record["units"]
    if any(every_unit_changes(p, top, recorded is not None) for p in changed):
        print("tidy_units: the checks or the build flags changed: every unit", file=sys.stderr)
        emit({e["file"] for e in entries})
        return
    units = {e["file"] for e in entries if os.path.realpath(e["file"]) in changed}
    if recorded is not None:
        for e in entries:
            if recorded.get(unit_key(e, top)) != normalised_command(e, top):
                if options.explain:
                    print(f"tidy_units: flags changed: {unit_key(e, top)}", file=sys.stderr)
                units.add(e["file"])
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
