#!/usr/bin/env python3
"""The code blocks of docs/*.md and README.md, checked as code (docs/CONTRIBUTING.md, "Code blocks").

Every fenced block of a checked language (cpp, yaml, xml, cmake) carries a marker, an HTML comment
on the line right before its fence, that says how it is checked:

  <!-- doc-block: program -->          cpp: a whole program (a main(), or a Catch2 test with
                                       CATCH_CONFIG_MAIN); built against the library and run
  <!-- doc-block: main -->             cpp: statements; #include and using lines go to the top, the
                                       rest into main(); built and run
  <!-- doc-block: compile -->          cpp: declarations or statements that need a context (a
                                       robot, a running loop): built, inside a function that is
                                       never called, not run
  <!-- doc-block: excerpt FILE -->     any language: the block is part of FILE (a file of the tree
                                       that is itself built and tested): its lines appear there in
                                       order (whitespace and trailing // or # comments aside); a
                                       line `...` stands for lines left out
  <!-- doc-block: net -->              xml: a whole Petri net; `tripodal-net check` must accept it
  <!-- doc-block: yaml -->             yaml: parsed (a part of a file shown alone)
  <!-- doc-block: xml -->              xml: well-formed (a part of a file, another program's file)
  <!-- doc-block: fragment REASON -->  not checked, for the REASON given (pseudo-code, a synopsis);
                                       listed in the summary, so that none goes unnoticed
  <!-- doc-block: shell -->            a shell block (sh or a plain fence): run with bash -eu in a
                                       scratch folder that links the tree's top folders (configs/,
                                       tests/, ...), the project's tools first on PATH; must exit 0
  <!-- doc-block: transcript -->       a shell session: each `$ command` line is run as above, and
                                       the lines shown after it must appear in what it prints, in
                                       order (a line `...` stands for lines left out); its exit
                                       status is not checked (transcripts show errors too)

Shell blocks without a marker are not run (many need a robot, a network, minutes of time).

A block of a checked language without a marker is an error. Subcommands:

  doc_blocks.py [--root DIR] check [--net-tool PATH]   the excerpts, nets and yaml; fails naming FILE:LINE
  doc_blocks.py extract --out DIR         writes each program/main/compile block as DIR/<doc>_<line>.cpp
                                          and DIR/blocks.cmake (the kinds), for tests/docs/CMakeLists.txt
"""
from __future__ import annotations

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
CHECKED = {"cpp", "yaml", "xml", "cmake"}
FENCE_RE = re.compile(r"^(\s*)```(\w*)\s*$")
MARKER_RE = re.compile(r"^\s*<!--\s*doc-block:\s*(\w[\w-]*)\s*(.*?)\s*-->\s*$")
KINDS = {"program", "main", "compile", "excerpt", "net", "yaml", "xml", "fragment", "shell", "transcript"}
SHELL_LANGS = {"", "sh", "bash", "shell", "console"}
CPP_KINDS = {"program", "main", "compile"}


class Block:
    def __init__(self, doc: str, line: int, lang: str, text: list[str], kind: str | None, arg: str):
        self.doc, self.line, self.lang, self.text, self.kind, self.arg = doc, line, lang, text, kind, arg

    @property
    def where(self) -> str:
        return f"{os.path.relpath(self.doc, ROOT)}:{self.line}"

    @property
    def stem(self) -> str:
        return os.path.splitext(os.path.basename(self.doc))[0].replace("-", "_") + f"_{self.line}"


def docs() -> list[str]:
    return sorted(glob.glob(os.path.join(ROOT, "docs", "**", "*.md"), recursive=True)) + [os.path.join(ROOT, "README.md")]


def blocks_of(doc: str) -> list[Block]:
    lines = open(doc, encoding="utf-8").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        m = FENCE_RE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang = m.group(1), m.group(2)
        j = i + 1
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            j += 1
        body = [l[len(indent):] if l.startswith(indent) else l for l in lines[i + 1:j]]
        kind, arg = None, ""
        k = i - 1
        if k >= 0:
            mm = MARKER_RE.match(lines[k])
            if mm:
                kind, arg = mm.group(1), mm.group(2)
        out.append(Block(doc, i + 1, lang, body, kind, arg))
        i = j + 1
    return out


def normalize(line: str, lang: str) -> str:
    s = line.strip()
    if lang in ("cpp",):
        s = re.sub(r"\s*//.*$", "", s) if not re.search(r'"[^"]*//', s) else s
    elif lang in ("yaml", "cmake"):
        s = re.sub(r"\s+#.*$", "", s)
    return re.sub(r"\s+", " ", s).strip()


def check_excerpt(b: Block) -> str | None:
    path = os.path.join(ROOT, b.arg)
    if not b.arg or not os.path.isfile(path):
        return f"excerpt of '{b.arg}', which is not a file of the tree"
    source = [normalize(l, b.lang) for l in open(path, encoding="utf-8").read().split("\n")]
    at = 0
    for n, raw in enumerate(b.text):
        line = normalize(raw, b.lang)
        if not line or line in ("...", "// ...", "# ...", "<!-- ... -->"):
            continue
        try:
            at = source.index(line, at) + 1
        except ValueError:
            where = "anywhere" if line not in source else "after the lines before it"
            return f"line {b.line + 1 + n} ('{raw.strip()}') is not in {b.arg} {where}"
    return None


def check_yaml(b: Block) -> str | None:
    try:
        import yaml  # python3-yaml (scripts/install-deps.sh)
    except ImportError:
        return "python3-yaml is missing (scripts/install-deps.sh)"
    try:
        yaml.safe_load("\n".join(b.text))
    except yaml.YAMLError as e:
        return f"not YAML: {e}".replace("\n", " ")
    return None


def check_xml(b: Block) -> str | None:
    import xml.etree.ElementTree as ET
    try:
        ET.fromstring("\n".join(b.text))
    except ET.ParseError as e:
        return f"not well-formed XML: {e}"
    return None


def check_net(b: Block, tool: str | None) -> str | None:
    if tool is None:
        return "a net block needs --net-tool (tripodal-net)"
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, b.stem + ".xml")
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(b.text) + "\n")
        r = subprocess.run([tool, "check", path], capture_output=True, text=True)
        if r.returncode != 0:
            return f"tripodal-net check exits {r.returncode}:\n{r.stdout}{r.stderr}"
    return None


def scratch_folder() -> str:
    """A folder to run shell blocks in: the tree's top folders linked, so that relative paths of
    the docs (configs/..., tests/data/...) resolve and what the commands write stays out of the tree."""
    d = tempfile.mkdtemp(prefix="doc_blocks_")
    for name in os.listdir(ROOT):
        if not name.startswith(".") and name != "build" and os.path.isdir(os.path.join(ROOT, name)):
            os.symlink(os.path.join(ROOT, name), os.path.join(d, name))
    return d


def run_shell(command: str, bin_dirs: list[str], cwd: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([os.path.abspath(b) for b in bin_dirs] + [env.get("PATH", "")])
    return subprocess.run(["bash", "-euc", command], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def check_shell(b: Block, bin_dirs: list[str]) -> str | None:
    cwd = scratch_folder()
    r = run_shell("\n".join(b.text), bin_dirs, cwd)
    shutil.rmtree(cwd, ignore_errors=True)
    if r.returncode != 0:
        return f"the commands exit {r.returncode}:\n{r.stdout}{r.stderr}"
    return None


def check_transcript(b: Block, bin_dirs: list[str]) -> str | None:
    cwd = scratch_folder()
    steps: list[tuple[int, str, list[str]]] = []
    for n, line in enumerate(b.text):
        if line.startswith("$ "):
            steps.append((n, line[2:], []))
        elif steps and steps[-1][1].endswith("\\") and not steps[-1][2]:
            steps[-1] = (steps[-1][0], steps[-1][1] + "\n" + line, [])
        elif steps:
            steps[-1][2].append(line)
    if not steps:
        return "a transcript without a `$ command` line"
    for n, command, shown in steps:
        r = run_shell(command, bin_dirs, cwd)
        shutil.rmtree(cwd, ignore_errors=True) if n == steps[-1][0] else None
        printed = [re.sub(r"\s+", " ", l).strip() for l in (r.stdout + r.stderr).split("\n")]
        at = 0
        for want in shown:
            w = re.sub(r"\s+", " ", want).strip()
            if not w or w == "...":
                continue
            # A shown line may be cut short: it matches a printed line it begins.
            found = next((i for i in range(at, len(printed)) if printed[i].startswith(w)), None)
            if found is not None:
                at = found + 1
            else:
                return (f"'{want.strip()}' (the output shown after the command of line {b.line + 1 + n}) is not in what it prints "
                        f"(exit {r.returncode}):\n{r.stdout}{r.stderr}")
    return None


def all_blocks() -> tuple[list[Block], list[str]]:
    blocks, errors = [], []
    for doc in docs():
        for b in blocks_of(doc):
            if b.lang not in CHECKED and not (b.lang in SHELL_LANGS and b.kind is not None):
                continue
            if b.kind is None:
                errors.append(f"{b.where}: a {b.lang} block without a marker; put <!-- doc-block: KIND ... --> on the "
                              f"line before its fence (docs/CONTRIBUTING.md)")
            elif b.kind not in KINDS:
                errors.append(f"{b.where}: unknown doc-block kind '{b.kind}'; expected one of {', '.join(sorted(KINDS))}")
            elif b.kind in ("shell", "transcript") and b.lang not in SHELL_LANGS:
                errors.append(f"{b.where}: doc-block '{b.kind}' is for shell blocks, this one is {b.lang}")
            elif b.kind in CPP_KINDS and b.lang != "cpp":
                errors.append(f"{b.where}: doc-block '{b.kind}' is for cpp blocks, this one is {b.lang}")
            elif b.kind == "fragment" and not b.arg:
                errors.append(f"{b.where}: a fragment says why it is not checked (<!-- doc-block: fragment REASON -->)")
            else:
                blocks.append(b)
    return blocks, errors


def cmd_check(args) -> int:
    blocks, errors = all_blocks()
    counts: dict[str, int] = {}
    fragments = []
    for b in blocks:
        counts[b.kind] = counts.get(b.kind, 0) + 1
        problem = None
        if b.kind == "excerpt":
            problem = check_excerpt(b)
        elif b.kind == "yaml":
            problem = check_yaml(b)
        elif b.kind == "xml":
            problem = check_xml(b)
        elif b.kind == "net":
            problem = check_net(b, args.net_tool)
        elif b.kind == "shell":
            problem = check_shell(b, args.bin_dir)
        elif b.kind == "transcript":
            problem = check_transcript(b, args.bin_dir)
        elif b.kind == "fragment":
            fragments.append(f"  {b.where}: {b.arg}")
        if problem:
            errors.append(f"{b.where}: {problem}")
    for e in errors:
        print(e)
    summary = ", ".join(f"{n} {k}" for k, n in sorted(counts.items()))
    print(f"doc_blocks: {len(blocks)} marked blocks ({summary}); {len(errors)} problems", file=sys.stderr)
    if fragments:
        print("not checked (fragments):\n" + "\n".join(fragments), file=sys.stderr)
    return 1 if errors else 0


def cpp_source(b: Block) -> str:
    head = [f"// {b.where}, doc-block {b.kind}: generated by scripts/doc_blocks.py"]
    if b.kind == "program":
        return "\n".join(head + [f'#line {b.line + 1} "{os.path.relpath(b.doc, ROOT)}"'] + b.text) + "\n"
    top, body, first_body = [], [], None
    for n, line in enumerate(b.text):
        if line.startswith(("#include", "using namespace", "using ")) and not body:
            top.append(f'#line {b.line + 1 + n} "{os.path.relpath(b.doc, ROOT)}"')
            top.append(line)
        else:
            if first_body is None:
                first_body = n
            body.append(line)
    line_of_body = b.line + 1 + (first_body or 0)
    if b.kind == "main":
        wrapped = ["int main() {", f'#line {line_of_body} "{os.path.relpath(b.doc, ROOT)}"'] + body + ["  return 0;", "}"]
    else:  # compile: never called, but every statement type-checked
        wrapped = ["[[maybe_unused]] static void doc_block() {", f'#line {line_of_body} "{os.path.relpath(b.doc, ROOT)}"'] + body + ["}"]
    return "\n".join(head + top + wrapped) + "\n"


def cmd_extract(args) -> int:
    # Blocks without a valid marker are left out here and reported by `check` (a ctest test), so
    # that a doc being written does not stop the build from configuring.
    blocks, _ = all_blocks()
    os.makedirs(args.out, exist_ok=True)
    entries = []
    for b in blocks:
        if b.kind not in CPP_KINDS:
            continue
        path = os.path.join(args.out, b.stem + ".cpp")
        text = cpp_source(b)
        # Rewritten only when changed, so that a reconfigure does not rebuild every block.
        if not os.path.exists(path) or open(path, encoding="utf-8").read() != text:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        entries.append(f"{b.stem} {b.kind}")
    with open(os.path.join(args.out, "blocks.cmake.tmp"), "w", encoding="utf-8") as f:
        f.write("set(TRIPODAL_DOC_BLOCKS\n" + "".join(f"  \"{e}\"\n" for e in entries) + ")\n")
    os.replace(os.path.join(args.out, "blocks.cmake.tmp"), os.path.join(args.out, "blocks.cmake"))
    print(f"doc_blocks: {len(entries)} C++ blocks written to {args.out}")
    return 0


def main() -> int:
    global ROOT
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--root", default=ROOT, help="the tree whose docs are checked (default: this script's)")
    sub = p.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("check")
    c.add_argument("--net-tool")
    c.add_argument("--bin-dir", action="append", default=[], help="put first on PATH for shell blocks (repeatable)")
    e = sub.add_parser("extract")
    e.add_argument("--out", required=True)
    args = p.parse_args()
    ROOT = os.path.abspath(args.root)
    return cmd_check(args) if args.cmd == "check" else cmd_extract(args)


if __name__ == "__main__":
    sys.exit(main())
