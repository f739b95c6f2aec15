#!/usr/bin/env python3
"""Checks that the documentation names code that exists (docs/CONTRIBUTING.md, "Docs name real code").

Reads docs/*.md and README.md, and the comments of the sources, and reports every name that the tree
does not have, as FILE:LINE: what:

  - a file path (src/..., include/..., tests/..., docs/..., configs/..., a header as
    tripodal/<area>/<name>.hpp, a markdown link to a file) that does not exist; also in the
    comments of include/, src/, tools/, tests/, examples/, bench/, fuzz/, scripts/, cmake/;
  - a type name in backquotes (`CBehavior`, `BhAutoMove`, `tripodal::RobotHarness`) that no
    source declares (class, struct, enum, alias, namespace, function) nor registers by name (a
    string literal: manifests, profile types);
  - a profile key in backquotes (`loops:`, `sequencing_period_s:`) that neither the profile loader
    (the keys src/**.cpp hands to expect_keys) nor a configuration under configs/ knows.

Names of other projects are listed in EXTERNAL below. A name a doc uses on purpose for something
that does not exist (a wrong example, a removed feature) is marked on its line with
`<!-- check-docs: ignore NAME -->`.

Usage: scripts/check_docs.py [--root DIR]   exit 0: clean, 1: findings (printed), 2: usage.
"""
from __future__ import annotations

import argparse
import glob
import os
import re
import sys

CODE_DIRS = ["include", "src", "tools", "tests", "examples", "bench", "fuzz"]
COMMENT_DIRS = CODE_DIRS + ["scripts", "cmake", ".ci", "configs"]
TOP_DIRS = ["src", "include", "tests", "tools", "configs", "docs", "examples", "scripts", "bench", "fuzz",
            "cmake", "schema", ".ci"]

# Names from outside the tree that docs may name: the standard library, the dependencies, formats.
EXTERNAL = {
    "Catch", "Catch2", "YAML", "Eigen", "Node", "XMLElement", "XMLDocument", "GTest", "Xapian", "CLI", "App",
    "CycloneDDS", "DDS", "ROS", "ROS2", "Nav2", "AMCL", "MCAP", "CDR", "IDL", "JSON", "HTTP", "WebSocket",
    "UART", "CRC", "PGM", "PNG", "SVG", "BM25", "SLAM", "CARMEN", "RPLIDAR", "LCD", "LED", "UV", "TSan",
    "ASan", "UBSan", "LSan", "CMake", "CTest", "CI", "GPU", "CPU", "API", "ABI", "SI", "TCP", "UDP", "IP",
    "EOF", "NaN", "Inf", "OK", "ERROR", "INFO", "WARN", "TODO", "NOTE", "README", "CONTRIBUTING",
    "RTPS", "QoS", "TF", "URDF", "SDF", "XML", "YAML_CPP", "HRI", "PSR", "PSR2", "Jinny", "BT",
    "BehaviorTree", "BT_REGISTER_NODES", "LogicError", "RuntimeError", "SIGINT", "SIGTERM", "SIGPIPE",
    "EINTR", "EAGAIN", "ENOENT", "O_NONBLOCK", "TIOCSWINSZ", "B115200", "Ninja", "Release", "Debug",
    "RelWithDebInfo", "ON", "OFF", "PUBLIC", "PRIVATE", "INTERFACE", "REQUIRED", "COMPONENTS", "CONFIG",
    "PATH", "HOME", "CXX", "CXXFLAGS", "LD_LIBRARY_PATH", "CMAKE_PREFIX_PATH", "CMAKE_BUILD_TYPE",
    "CCACHE_BASEDIR", "CCACHE_NOHASHDIR", "BUILD_ROOT", "JOBS", "FUZZ_RUNS", "FUZZ_SEED", "A1", "A2",
    "Fast", "FastDDS", "Cyclone", "OpenCV", "Graphviz", "Agraph_t", "GVC_t", "Chromium", "Selenium",
    "Origin", "Host", "Peers", "ClockQoS",  # HTTP headers, Cyclone DDS's configuration, rclcpp
}
EXTERNAL_FILES = {"catch.hpp"}
# std:: and friends: any name under these namespaces is external.
EXTERNAL_NAMESPACES = ("std::", "Catch::", "YAML::", "Eigen::", "tinyxml2::", "fmt::", "spdlog::", "CLI::",
                       "Xapian::", "benchmark::", "nlohmann::", "dds_", "eprosima::", "rclcpp::", "BT::",
                       "nav2_", "ros2_control", "hardware_interface::", "controller_interface::")
# ROS 2 message types as DDS names them (sensor_msgs::msg::dds_::LaserScan_).
EXTERNAL_RE = re.compile(r"^\w+::msg::dds_::\w+$")

PATH_RE = re.compile(r"(?<![\w/.~$-])((?:%s)/[A-Za-z0-9_.*/+-]*(?:[A-Za-z0-9_*]|\.\{[\w,]+\}))" % "|".join(re.escape(d) for d in TOP_DIRS))
HEADER_RE = re.compile(r"(?<![\w/.-])(tripodal/[a-z_]+/[A-Za-z0-9_/]+\.hpp)")
BARE_FILE_RE = re.compile(r"(?<![\w/.{(-])([A-Za-z0-9_-]+\.(?:hpp|cpp|md|py|sh))\b(?![/{])")
LINK_RE = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
TICK_RE = re.compile(r"`([^`\n]+)`")
TYPE_RE = re.compile(r"^(?:tripodal::)?((?:[A-Za-z_][A-Za-z0-9_]*::)*[A-Z][A-Za-z0-9_]*)(?:<.*>)?(?:\(\))?$")
KEY_RE = re.compile(r"^([a-z][a-z0-9_]*):$")
IGNORE_RE = re.compile(r"<!--\s*check-docs:\s*ignore\s+([^>]*?)\s*-->")
DECL_RE = re.compile(r"\b(?:class|struct|enum(?:\s+class)?|union|using|concept|typedef\s+[\w:<>, ]+)\s+([A-Za-z_]\w*)")
NAMESPACE_RE = re.compile(r"\bnamespace\s+([\w:]+)")
FUNC_RE = re.compile(r"\b([A-Za-z_]\w*)\s*\(")
STRING_RE = re.compile(r'"([A-Za-z_][A-Za-z0-9_.]*)"')
EXPECT_KEYS_RE = re.compile(r"expect_keys\([^{]*\{([^}]*)\}", re.S)
YAML_KEY_RE = re.compile(r"^\s*(?:-\s+)?([a-z][a-z0-9_]*):", re.M)
YAML_FLOW_KEY_RE = re.compile(r"[{,]\s*([a-z][a-z0-9_]*):")
MACRO_RE = re.compile(r"#\s*define\s+([A-Z_][A-Z0-9_]*)")
CMAKE_NAME_RE = re.compile(r"\b(TRIPODAL_[A-Z0-9_]+|tripodal_[a-z0-9_]+)\b")


def read(path: str) -> str:
    with open(path, encoding="utf-8", errors="replace") as f:
        return f.read()


def files_under(root: str, dirs: list[str], exts: tuple[str, ...]) -> list[str]:
    out = []
    for d in dirs:
        for base, subdirs, names in os.walk(os.path.join(root, d)):
            subdirs[:] = [s for s in subdirs if not s.startswith("build")]
            out += [os.path.join(base, n) for n in names if n.endswith(exts)]
    return sorted(out)


class Tree:
    """What the tree declares, registers and accepts: the references the docs are checked against."""

    def __init__(self, root: str):
        self.root = root
        self.declared: set[str] = set()
        self.strings: set[str] = set()
        self.profile_keys: set[str] = set()
        sources = files_under(root, CODE_DIRS, (".hpp", ".cpp", ".h", ".in", ".idl"))
        for path in sources:
            text = read(path)
            self.declared.update(DECL_RE.findall(text))
            for ns in NAMESPACE_RE.findall(text):
                self.declared.update(ns.split("::"))
            self.declared.update(FUNC_RE.findall(text))
            self.declared.update(MACRO_RE.findall(text))
            self.strings.update(STRING_RE.findall(text))
            for keys in EXPECT_KEYS_RE.findall(text):
                self.profile_keys.update(re.findall(r'"([a-z][a-z0-9_]*)"', keys))
            # Keys read one by one (v["name"], require(n, "name", ...), key == "name").
            self.profile_keys.update(re.findall(r'(?:\[|key == |require\(\w+, )"([a-z][a-z0-9_]*)"', text))
        # Names the nets and knowledge bases give (behaviors, places, events) count as registered.
        for path in files_under(root, ["configs", "examples", "tests/data", "docs"], (".xml",)):
            self.strings.update(re.findall(r'="([A-Za-z_][A-Za-z0-9_.]*)"', read(path)))
        for path in files_under(root, ["configs", "examples", "tests/data", "bench"], (".yaml", ".yml")):
            text = read(path)
            self.profile_keys.update(YAML_KEY_RE.findall(text))
            self.profile_keys.update(YAML_FLOW_KEY_RE.findall(text))
        for path in files_under(root, ["."], ("CMakeLists.txt", ".cmake")):
            self.declared.update(CMAKE_NAME_RE.findall(read(path)))
        self.known = self.declared | self.strings
        self.basenames: set[str] = set()
        for base, subdirs, names in os.walk(root):
            subdirs[:] = [d for d in subdirs if not d.startswith(("build", ".git"))]
            self.basenames.update(names)

    def has_path(self, rel: str) -> bool:
        rel = rel.rstrip("/.")
        brace = re.match(r"^(.*)\.\{([\w,]+)\}$", rel)
        if brace:  # src/x/y.{hpp,cpp}: every one
            return all(self.has_path(brace.group(1) + "." + ext) for ext in brace.group(2).split(","))
        full = os.path.join(self.root, rel)
        if "*" in rel:
            return bool(glob.glob(full))
        # A unit named by its stem (src/core/xml_document: its .hpp and .cpp).
        return os.path.exists(full) or bool(glob.glob(full + ".*"))

    def has_type(self, name: str) -> bool:
        parts = [p for p in name.split("::") if p]
        return all(p in self.known or p in EXTERNAL for p in parts)


class Report:
    def __init__(self, root: str):
        self.root = root
        self.findings: list[str] = []

    def add(self, path: str, line: int, what: str) -> None:
        self.findings.append(f"{os.path.relpath(path, self.root)}:{line}: {what}")


def check_paths(tree: Tree, report: Report, path: str, lineno: int, line: str, in_doc: bool) -> None:
    for m in PATH_RE.finditer(line):
        rel = m.group(1).rstrip(".,;:")
        if rel.endswith((".", "/")) or "..." in rel:
            continue
        # Generated or build-time paths, placeholders.
        if re.search(r"(^|/)(build|NAME|AREA|X|FILE)(/|$)|<|\$", rel):
            continue
        if not tree.has_path(rel):
            report.add(path, lineno, f"names '{rel}', which does not exist")
    for m in HEADER_RE.finditer(line):
        rel = m.group(1)
        if line[: m.start()].endswith(("include/", "src/", "tests/")):
            continue
        if not tree.has_path("include/" + rel):
            report.add(path, lineno, f"names header '{rel}', which include/ does not have")
    for m in BARE_FILE_RE.finditer(line):
        name = m.group(1)
        if name not in tree.basenames and name not in EXTERNAL_FILES and not re.match(r"^(my|your|foo|bar|x|a|out|file|robot|net|map|run|excerpt|trace|world|profile|winch|plugin|app|tasks|patrol|scenario|config)[\w-]*\.", name):
            report.add(path, lineno, f"names file '{name}', which the tree does not have")
    if in_doc:
        for m in LINK_RE.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z]+:", target) or target.startswith("/"):
                continue
            full = os.path.normpath(os.path.join(os.path.dirname(path), target))
            if not os.path.exists(full):
                report.add(path, lineno, f"links to '{target}', which does not exist")


def check_doc(tree: Tree, report: Report, path: str) -> None:
    fenced = False
    for lineno, line in enumerate(read(path).splitlines(), 1):
        ignored = set()
        for m in IGNORE_RE.finditer(line):
            ignored.update(m.group(1).split())
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        check_paths(tree, report, path, lineno, line, in_doc=True)
        if fenced:
            continue  # code blocks are compiled and loaded by scripts/doc_blocks.py
        for m in TICK_RE.finditer(line):
            token = m.group(1).strip()
            if token in ignored:
                continue
            key = KEY_RE.match(token)
            if key:
                if key.group(1) not in tree.profile_keys:
                    report.add(path, lineno, f"names profile key '{token}', which no loader or configuration knows")
                continue
            t = TYPE_RE.match(token)
            if not t or token.startswith(EXTERNAL_NAMESPACES) or EXTERNAL_RE.match(token):
                continue
            name = t.group(1)
            if name.upper() == name:
                continue  # an abbreviation, a macro or a variable of the system (NDEBUG, SCHED_FIFO), not a type
            if not tree.has_type(name):
                report.add(path, lineno, f"names '{name}', which no source declares or registers")


BEHAVIOR_MANIFEST_RE = re.compile(
    r'(?:ManifestBuilder\(\s*"(\w+)"\s*,\s*(?:tripodal::)?ModuleKind::behavior|behavior_manifest\(\s*"(\w+)")(.*?)(?:\.build\(\)|;)',
    re.S)
OUTPUT_RE = re.compile(r'\.output\(\s*"(\w+\*?)"')


def coordinator_vocabulary(root: str) -> tuple[str, str]:
    """What behaviors write and what the coordinator writes, as the layering check has them."""
    text = read(os.path.join(root, "src", "robot", "layering.cpp"))
    m = re.search(r'"fuses the commands[^"]*",\s*\{"(\w+)\*"\},\s*\{"(\w+)"\}', text)
    if m is None:
        raise SystemExit("check_docs: src/robot/layering.cpp no longer declares the coordinator's "
                         "inputs and outputs as this script reads them; update coordinator_vocabulary()")
    return m.group(1), m.group(2)


def check_vocabulary(root: str, report: Report, path: str) -> None:
    """A behavior's manifest writes what the coordinator fuses (behavior_command), nothing else."""
    command, _ = coordinator_vocabulary(root)
    text = read(path)
    for m in BEHAVIOR_MANIFEST_RE.finditer(text):
        name = m.group(1) or m.group(2)
        for out in OUTPUT_RE.finditer(m.group(3)):
            if out.group(1) != command:
                line = text.count("\n", 0, m.start(3) + out.start()) + 1
                report.add(path, line, f"behavior '{name}' declares output '{out.group(1)}'; a behavior writes "
                           f"'{command}', which the coordinator fuses (src/robot/layering.cpp)")


COMMENT_LINE_RE = re.compile(r"^\s*(?://|#|\*|/\*)(.*)$")


def check_comments(tree: Tree, report: Report, path: str) -> None:
    # The configurations: comments and values alike name files (bench/ and tests/ YAML name build outputs).
    whole = os.path.relpath(path, tree.root).startswith("configs" + os.sep)
    for lineno, line in enumerate(read(path).splitlines(), 1):
        if "check-docs: ignore" in line:
            continue
        if whole:
            check_paths(tree, report, path, lineno, line, in_doc=False)
            continue
        m = COMMENT_LINE_RE.match(line)
        if m is None:
            trailing = line.find("// ")
            if trailing < 0:
                continue
            text = line[trailing:]
        else:
            text = m.group(1)
        check_paths(tree, report, path, lineno, text, in_doc=False)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    tree = Tree(root)
    report = Report(root)
    docs = sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True)) + [os.path.join(root, "README.md")]
    for doc in docs:
        check_doc(tree, report, doc)
        check_vocabulary(root, report, doc)
    for example in files_under(root, ["examples"], (".cpp", ".hpp")):
        check_vocabulary(root, report, example)
    for src in files_under(root, COMMENT_DIRS, (".hpp", ".cpp", ".h", ".sh", ".py", ".cmake", ".txt", ".in", ".yaml", ".xml")):
        # tests/data/ holds fixtures: trees of their own (tests/data/layers/) and wrong files on purpose.
        if not os.path.relpath(src, root).startswith(os.path.join("tests", "data") + os.sep):
            check_comments(tree, report, src)
    for f in report.findings:
        print(f)
    print(f"check_docs: {len(docs)} docs and the comments of the sources: {len(report.findings)} findings",
          file=sys.stderr)
    return 1 if report.findings else 0


if __name__ == "__main__":
    sys.exit(main())
