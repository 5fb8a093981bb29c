#!/usr/bin/python3
"""The documentation's links resolve, and every file format has its schema page.

1. Every relative link and image in README.md, ARCHITECTURE.md and docs/*.md points to a file or folder
   of the repository, and a `#anchor` (in the same page or another markdown page) to a heading of that
   page, with GitHub's anchor rule (lower case; punctuation other than '-' and '_' dropped; spaces
   become '-'; a repeated heading gets -1, -2, ...). Links in code blocks and inline code are not links.
2. Every cgd_format value the code writes (schema::write_common(file, "FORMAT", ...) in C++,
   attrs["cgd_format"] = "FORMAT" in Python) is documented on a docs/schema-*.md page that says
   cgd_format = "FORMAT".

usage: /usr/bin/python3 tests/docs/check_links.py [REPO_ROOT]   (default: CGD_SOURCE_DIR, else this file's ../..)
Exit status 0 when everything resolves, 1 otherwise (each problem on stderr as FILE:LINE: ...).
"""
import os
import re
import sys
import unicodedata

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s{0,3}(```|~~~)")


def slug(text):
    """GitHub's heading anchor of the heading's rendered text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links and images: their text
    text = text.replace("`", "")
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = text.strip().lower()
    # github-slugger keeps letters, numbers and combining marks (the macron of φ̄ is U+0304, category Mn)
    text = "".join(c for c in text if c.isalnum() or unicodedata.category(c).startswith("M") or c in " -_")
    return text.replace(" ", "-")


def lines_outside_code(path):
    """(line number, text, text without inline code) of the lines outside fenced code blocks."""
    inside = False
    with open(path, encoding="utf-8") as fh:
        for number, line in enumerate(fh, 1):
            if FENCE.match(line):
                inside = not inside
                continue
            if inside or line.startswith("    ") and not line.strip().startswith(("-", "*", "|", "[")):
                continue
            yield number, line, re.sub(r"`[^`]*`", "", line)


def anchors(path, cache={}):
    if path not in cache:
        seen, found = {}, set()
        for _, line, _ in lines_outside_code(path):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
        for _, line, _ in lines_outside_code(path):  # explicit anchors: <a name="..."> / id="..."
            for a in re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", line):
                found.add(a)
        cache[path] = found
    return cache[path]


def check_links(root, pages):
    problems = []
    for page in pages:
        for number, _, line in lines_outside_code(page):
            targets = LINK.findall(line)
            m = REFERENCE.match(line)
            if m:
                targets.append(m.group(1))
            for target in targets:
                if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I) or target.startswith("//"):
                    continue  # http:, https:, mailto: ...
                where = f"{os.path.relpath(page, root)}:{number}"
                file_part, _, anchor = target.partition("#")
                dest = page if not file_part else os.path.normpath(os.path.join(os.path.dirname(page), file_part))
                if not os.path.realpath(dest).startswith(os.path.realpath(root) + os.sep) and dest != page:
                    problems.append(f"{where}: {target}: points outside the repository")
                    continue
                if not os.path.exists(dest):
                    problems.append(f"{where}: {target}: no such file {os.path.relpath(dest, root)}")
                    continue
                if anchor:
                    if not dest.endswith(".md"):
                        problems.append(f"{where}: {target}: an anchor into a file that is not markdown")
                    elif anchor not in anchors(dest):
                        problems.append(f"{where}: {target}: no heading with anchor #{anchor} in "
                                        f"{os.path.relpath(dest, root)}")
    return problems


def check_formats(root):
    """Every cgd_format the code writes has a docs/schema-*.md page saying cgd_format = "FORMAT"."""
    written = {}
    # the formats' rows (core/schema/check.hpp: `inline constexpr Format kSnapshot{"snapshot", ...}`) and the
    # Python writers
    patterns = [re.compile(r"constexpr\s+Format\s+\w+\s*\{\s*\"(\w+)\""),
                re.compile(r"attrs\[\s*[\"']cgd_format[\"']\s*\]\s*=\s*[\"'](\w+)[\"']")]
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if not d.startswith(".") and d not in ("build", "out", "tests")]
        for name in files:
            if not name.endswith((".cpp", ".hpp", ".py")) and name != "cgd-show":
                continue
            path = os.path.join(folder, name)
            with open(path, encoding="utf-8", errors="replace") as fh:
                text = fh.read()
            for pattern in patterns:
                for fmt in pattern.findall(text):
                    written.setdefault(fmt, os.path.relpath(path, root))
    docs = os.path.join(root, "docs")
    schema_text = ""
    for name in sorted(os.listdir(docs)):
        if name.startswith("schema-") and name.endswith(".md"):
            with open(os.path.join(docs, name), encoding="utf-8") as fh:
                schema_text += fh.read()
    problems = []
    for fmt, source in sorted(written.items()):
        if f'cgd_format = "{fmt}"' not in schema_text:
            problems.append(f'{source}: writes cgd_format "{fmt}", but no docs/schema-*.md says cgd_format = "{fmt}"')
    if not written:
        problems.append("found no cgd_format written anywhere: the patterns of check_formats are out of date")
    return problems, written


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("CGD_SOURCE_DIR",
                                                                                 os.path.join(here, "..", "..")))
    pages = [os.path.join(root, "README.md"), os.path.join(root, "ARCHITECTURE.md")]
    docs = os.path.join(root, "docs")
    pages += sorted(os.path.join(docs, n) for n in os.listdir(docs) if n.endswith(".md"))
    pages = [p for p in pages if os.path.exists(p)]
    problems = check_links(root, pages)
    format_problems, formats = check_formats(root)
    problems += format_problems
    for p in problems:
        print(p, file=sys.stderr)
    print(f"check_links: {len(pages)} pages, formats {', '.join(sorted(formats))}: "
          f"{'OK' if not problems else str(len(problems)) + ' problem(s)'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
