#!/usr/bin/python3
"""Every file name the Python tools read is in the schema (issue 30): each string a tool in tools/ looks up in an
h5py file or attribute set -- f["particles/position"], a.get("width_exponent"), "bands" in f -- has each of its
path components written as `name` on a docs/schema-*.md page, the schema the tools and the C++ readers share.

What counts as a lookup in an h5py object: a subscript, .get() or `in` test on a variable of the names the tools
use for files, groups and attribute sets (f, g, h, s, a, p, b, t, c, d, ps, grp, sn, runs) or on `.attrs`,
with a constant string, unless the same file also stores that key into a dict of its own (a subscript
assignment or a dict literal: the tools' in-memory rows).

The same check for the C++ schema layer (every core/schema/*.cpp and *.hpp: the code that names file contents):
every
attribute and dataset name it spells -- a name constant (constexpr const char* kX = "name"), a row of a name table
({"name", &Struct::member}), a literal path ("/bins/phi_edges") or a name given to set_attr, has_attr, attr_*,
finite_attr(s), require_attr or child -- is named on a docs/schema-*.md page, so that a name changed in the code
without its page fails here.

Two more checks of "one home per format, one spelling per idea" (issue 30):
- outside core/schema/ (core/, sim/, filter/, fit/, coarse/, generator/), no C++ code gives an HDF5 call of
  core/h5.hpp (set_attr, attr_*, write_rows, read_rows_*, exists, ...) a literal name: the stages fill and consume
  the schema's structs (NAMES_OUTSIDE_ALLOWED lists exceptions, and is empty).
- the retired spellings of version-1 files (base_drag, "tsc-grid", "tsc-deposit-interpolate") appear, outside
  comments, only in their format's upgrade path: core/schema/drag_model.cpp, core/schema/filtered.cpp and
  tools/cgd_schema.py; no other tool or stage reads or writes them; and the Python upgrade path spells what the
  C++ one does and reads a version-1 model (tests/data/half_box_v1.h5) alike.
Run by CTest (schema_tool_names).
"""
import ast
import os
import re
import sys

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
H5_VARIABLES = {"f", "g", "h", "s", "a", "p", "b", "t", "c", "d", "ps", "grp", "sn", "runs", "attrs"}


def documented_names():
    docs = os.path.join(ROOT, "docs")
    text = "".join(open(os.path.join(docs, n), encoding="utf-8").read()
                   for n in sorted(os.listdir(docs)) if n.startswith("schema-") and n.endswith(".md"))
    names = set()
    for quoted in re.findall(r"`/?([A-Za-z_][A-Za-z0-9_/<>]*)", text):
        names.update(quoted.split("/"))
    return names


def lookups(path):
    tree = ast.parse(open(path, encoding="utf-8").read(), path)
    own = set()  # keys of the tool's own dicts
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            own.update(k.value for k in node.keys if isinstance(k, ast.Constant) and isinstance(k.value, str))
        elif isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) and \
                isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
            own.add(node.slice.value)
    found = []
    for node in ast.walk(tree):
        key = base = None
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
            key, base = node.slice.value, node.value
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" and \
                node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
            key, base = node.args[0].value, node.func.value
        elif isinstance(node, ast.Compare) and isinstance(node.left, ast.Constant) and \
                isinstance(node.left.value, str) and len(node.ops) == 1 and isinstance(node.ops[0], (ast.In, ast.NotIn)):
            key, base = node.left.value, node.comparators[0]
        if key is None or key in own:
            continue
        root = base
        while isinstance(root, (ast.Subscript, ast.Attribute, ast.Call)):
            root = root.func if isinstance(root, ast.Call) else root.value
        on_attrs = isinstance(base, ast.Attribute) and base.attr == "attrs"
        if on_attrs or (isinstance(root, ast.Name) and root.id in H5_VARIABLES):
            found.append((node.lineno, key))
    return found


SCHEMA_SOURCES = tuple("schema/" + n for n in sorted(os.listdir(os.path.join(ROOT, "core", "schema")))
                       if n.endswith((".cpp", ".hpp")))
STAGE_FOLDERS = ("core", "sim", "filter", "fit", "coarse", "generator")
NAMES_OUTSIDE_ALLOWED = set()  # none: the physical system's attributes are core/schema/common.hpp's too
H5_CALL_WITH_LITERAL = re.compile(r"\.(?:set_attr|has_attr|attr_\w+|write_rows|write_replicated|write_block|read_rows_\w+|"
                                  r"exists|create_group|dims|is_integer)\(\s*\"")
RETIRED_SPELLINGS = ("base_drag", "tsc-grid", "tsc-deposit-interpolate")
UPGRADE_PATHS = {"core/schema/drag_model.cpp", "core/schema/filtered.cpp", "tools/cgd_schema.py"}
NAME = r"[A-Za-z_][A-Za-z0-9_]*"
SCHEMA_PATTERNS = [
    re.compile(r"constexpr const char\* k\w+ = \"(/?" + NAME + r"(?:/" + NAME + r")*)\";"),
    re.compile(r"\{\s*\"(" + NAME + r")\",\s*&"),
    re.compile(r"\"(/" + NAME + r"(?:/" + NAME + r")*)\""),
    re.compile(r"\b(?:set_attr|has_attr|attr_\w+|finite_attrs?|require_attr|child)\([^,()]+,\s*\"(" + NAME + r")\""),
]


def schema_names(path):
    """(line, name) of every file-content name a core/schema/ source spells."""
    found = []
    for number, line in enumerate(open(path, encoding="utf-8"), 1):
        if line.lstrip().startswith("//"):
            continue
        for pattern in SCHEMA_PATTERNS:
            found.extend((number, m.group(1)) for m in pattern.finditer(line))
    return sorted(set(found))


def code_lines(path):
    """(line number, text) of a source's lines without comments (// in C++; # and docstrings in Python)."""
    python = path.endswith(".py") or os.path.basename(path) == "cgd-show"
    quotes = ('"' * 3, "'" * 3)
    in_doc = False
    for number, line in enumerate(open(path, encoding="utf-8"), 1):
        stripped = line.strip()
        if python and stripped.startswith(quotes):
            if not (len(stripped) > 3 and stripped.endswith(stripped[:3])):
                in_doc = not in_doc
            continue
        if in_doc or stripped.startswith("#" if python else "//"):
            continue
        yield number, line.split("  #")[0] if python else line.split("//")[0]


def stage_sources():
    """The C++ sources of the stages: core/ (without core/schema/ and the HDF5 wrapper core/h5.*) and the tools' folders."""
    for folder in STAGE_FOLDERS:
        for base, dirs, files in os.walk(os.path.join(ROOT, folder)):
            if os.path.relpath(base, ROOT) == "core":
                dirs[:] = [d for d in dirs if d != "schema"]
            for n in sorted(files):
                if n.endswith((".cpp", ".hpp")) and not n.startswith("h5."):
                    yield os.path.join(base, n)


def names_outside_schema():
    """(problems, sources scanned): literal names given to HDF5 calls outside core/schema/, and retired spellings
    outside the upgrade paths."""
    problems, scanned = [], 0
    tools = os.path.join(ROOT, "tools")
    sources = list(stage_sources()) + [os.path.join(ROOT, "core", s) for s in SCHEMA_SOURCES] + \
        [os.path.join(tools, n) for n in sorted(os.listdir(tools)) if n.endswith(".py") or n == "cgd-show"]
    for path in sources:
        rel = os.path.relpath(path, ROOT)
        scanned += 1
        for number, line in code_lines(path):
            if not rel.startswith(("core/schema/", "tools/")) and rel not in NAMES_OUTSIDE_ALLOWED and \
                    H5_CALL_WITH_LITERAL.search(line):
                problems.append(f"{rel}:{number}: names file contents outside core/schema/: {line.strip()}")
            for retired in RETIRED_SPELLINGS:
                if rel not in UPGRADE_PATHS and re.search(r"(?<![\w-])" + re.escape(retired) + r"(?![\w-])", line):
                    problems.append(f"{rel}:{number}: spells '{retired}', a version-1 spelling that only the upgrade "
                                    f"paths ({', '.join(sorted(UPGRADE_PATHS))}) may know")
    return problems, scanned


def upgrade_paths_agree():
    """Problems: the Python upgrade path (tools/cgd_schema.py) spells what the C++ one does -- today's micro-law
    attribute and grid operator, version 1's spellings per format -- and reads a version-1 model,
    tests/data/half_box_v1.h5 (the three-run half-box model, version 1), as the C++ reader does (micro law
    beetstra, operator grid: DragModelSchema.AVersion1ModelStillReads)."""
    sys.path.insert(0, os.path.join(ROOT, "tools"))
    import cgd_schema
    problems = []

    def constant(source, name):
        m = re.search(r"constexpr const char\* " + name + r" = \"([^\"]+)\";", open(os.path.join(ROOT, source)).read())
        return m.group(1) if m else None

    expected = [
        ("core/schema/common.hpp", "kMicroLawAttribute", cgd_schema.MICRO_LAW),
        ("core/schema/drag_model.cpp", "kVersion1MicroLawAttribute", cgd_schema.VERSION1_MICRO_LAW["drag_model"]),
        ("core/schema/drag_model.cpp", "kVersion1GridOperator", cgd_schema.VERSION1_GRID_OPERATOR["drag_model"]),
        ("core/schema/filtered.cpp", "kVersion1GridOperator", cgd_schema.VERSION1_GRID_OPERATOR["filtered"]),
    ]
    for source, name, python in expected:
        cpp = constant(source, name)
        if cpp != python:
            problems.append(f"{source}: {name} = {cpp!r}, tools/cgd_schema.py says {python!r}")
    if '{CalibrationOperator::Grid, "grid"}' not in open(os.path.join(ROOT, "core/schema/calibration.cpp")).read() or \
            cgd_schema.GRID != "grid":
        problems.append("core/schema/calibration.cpp and tools/cgd_schema.py disagree on the grid operator's spelling")
    import h5py
    with h5py.File(os.path.join(ROOT, "tests", "data", "half_box_v1.h5"), "r") as f:
        got = (int(f.attrs["cgd_format_version"]), cgd_schema.micro_law(f.attrs), cgd_schema.calibration_operator(f.attrs))
    if got != (1, "beetstra", "grid"):
        problems.append(f"tests/data/half_box_v1.h5 through tools/cgd_schema.py: (version, micro law, operator) = {got}, "
                        "expected (1, 'beetstra', 'grid') as core/schema/drag_model.cpp reads it")
    return problems


def documented(part, names):
    # a prefix such as "width_" (of /width_<k>) stands for the names it begins
    return part in names or (part.endswith("_") and any(n.startswith(part) for n in names))


def main():
    names = documented_names()
    tools = os.path.join(ROOT, "tools")
    files = [os.path.join(tools, n) for n in sorted(os.listdir(tools)) if n.endswith(".py") or n == "cgd-show"]
    problems, count = [], 0
    for path in files:
        for line, key in lookups(path):
            count += 1
            missing = [part for part in key.split("/") if part and part not in names]
            if missing:
                problems.append(f"{os.path.relpath(path, ROOT)}:{line}: reads '{key}', and no docs/schema-*.md page "
                                f"names {', '.join(missing)}")
    schema_count = 0
    for source in SCHEMA_SOURCES:
        path = os.path.join(ROOT, "core", source)
        for line, key in schema_names(path):
            schema_count += 1
            missing = [part for part in key.split("/") if part and not documented(part, names)]
            if missing:
                problems.append(f"{os.path.relpath(path, ROOT)}:{line}: writes or reads '{key}', and no docs/schema-*.md "
                                f"page names {', '.join(missing)}")
    print(f"tool_names: {schema_count} names in the schema layer ({', '.join(SCHEMA_SOURCES)})")
    if schema_count < 150:
        print("FAIL: found fewer than 150 names in core/schema/: the patterns of this test are out of date")
        return 1
    outside, scanned = names_outside_schema()
    print(f"tool_names: {scanned} stage, schema and tool sources checked for names outside core/schema/ and retired "
          f"spellings: {'OK' if not outside else str(len(outside)) + ' found'}")
    if scanned < 100:
        print("FAIL: scanned fewer than 100 sources: the folders of this test are out of date")
        return 1
    problems += outside
    upgrade = upgrade_paths_agree()
    print(f"tool_names: the Python and C++ upgrade paths of version-1 files: {'OK' if not upgrade else 'disagree'}")
    problems += upgrade
    for p in problems:
        print(p)
    print(f"tool_names: {count} lookups in {len(files)} tools: {'OK' if not problems else str(len(problems)) + ' not in the schema'}")
    if count < 100:
        print("FAIL: found fewer than 100 lookups: the patterns of this test are out of date")
        return 1
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
