#!/usr/bin/env python3
"""Checks every relative link and #anchor of README.md and the book (docs/src/**/*.md).

    python3 scripts/check-doc-links.py      # exit 1, listing each broken link, when one is

For each inline link or image `[text](target)`, reference definition `[id]: target` and mdBook
`{{#include path[:anchor]}}` outside code (fenced blocks and code spans):
- a link with a scheme (https:, mailto:) is left alone;
- the path, relative to the file's folder, must exist; from a page of the book it must stay
  inside docs/src (the HTML book holds nothing else), from the README inside the repository;
- a `#anchor` must name a heading of the target page (or the same page), with mdBook's rule for
  heading ids, which GitHub's README rendering shares: the heading's text lowercased, spaces to
  `-`, everything but letters, digits, `-` and `_` dropped; a repeated heading gets `-1`, `-2`;
  a heading's `{#id}` attribute and HTML `id="..."` attributes count as anchors too;
- an include's anchor must have its `ANCHOR: name` line in the included file.
Standard library only.
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BOOK = ROOT / "docs/src"

FENCE = re.compile(r"^\s{0,3}(```+|~~~+)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
# [text](target) and ![alt](target); text may hold one level of brackets (an image in a link).
INLINE = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*(<[^>]*>|[^()\s]*(?:\([^()\s]*\)[^()\s]*)*)(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
INCLUDE = re.compile(r"\{\{#include\s+([^}\s]+)\s*\}\}")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
HEADING_ID = re.compile(r"\s*\{#([^}\s]+)\}\s*$")
HTML_ID = re.compile(r"""\bid\s*=\s*["']([^"']+)["']""")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def prose_lines(text):
    """(line number, line) outside fenced code blocks: each paragraph joined into one line (a
    link's text may break across lines), numbered by its first line, with code spans blanked;
    reference definitions and includes stay lines of their own."""
    fence, block, start = None, [], 0

    def flush():
        if block:
            joined = " ".join(block)
            yield start, CODE_SPAN.sub(lambda c: " " * len(c.group(0)), joined)
        block.clear()

    for number, line in enumerate(text.splitlines(), 1):
        m = FENCE.match(line)
        if m:
            mark = m.group(1)[0] * 3
            if fence is None:
                yield from flush()
                fence = mark
            elif mark == fence:
                fence = None
            continue
        if fence is not None:
            continue
        if not line.strip() or REFERENCE.match(line) or INCLUDE.search(line):
            yield from flush()
            if line.strip():
                yield number, line
            continue
        if not block:
            start = number
        block.append(line.strip())
    yield from flush()


def heading_id(text):
    """mdBook's id for a heading (utils::id_from_content + normalize_id)."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML tags
    text = text.replace("`", "")
    text = re.sub(r"(\*\*|__|\*)", "", text)
    out = []
    for ch in text.strip():
        if ch.isalnum() or ch in "_-":
            out.append(ch.lower() if ch.isascii() else ch)
        elif ch.isspace():
            out.append("-")
    return "".join(out)


_anchors = {}


def anchors(path):
    if path not in _anchors:
        text = path.read_text(encoding="utf-8")
        found, seen = set(), {}
        fence = None
        for line in text.splitlines():
            m = FENCE.match(line)
            if m:
                mark = m.group(1)[0] * 3
                if fence is None:
                    fence = mark
                elif mark == fence:
                    fence = None
                continue
            if fence is not None:
                continue
            found.update(HTML_ID.findall(line))
            h = HEADING.match(line)
            if not h:
                continue
            title = h.group(2)
            custom = HEADING_ID.search(title)
            if custom:
                found.add(custom.group(1))
                continue
            base = heading_id(title)
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
        _anchors[path] = found
    return _anchors[path]


def include_anchors(path):
    return set(re.findall(r"ANCHOR:\s*([\w-]+)", path.read_text(encoding="utf-8")))


def check_target(source, target, is_include):
    """None when the target resolves, else why it does not."""
    if target.startswith("<") and target.endswith(">"):
        target = target[1:-1]
    if not target or SCHEME.match(target) or target.startswith("//"):
        return None
    if is_include:
        path_part, _, anchor = target.partition(":")
    else:
        path_part, _, anchor = target.partition("#")
    path_part = path_part.split("?")[0]
    dest = (source.parent / path_part).resolve() if path_part else source
    limit = BOOK if source.resolve().is_relative_to(BOOK.resolve()) else ROOT
    if not dest.is_relative_to(limit.resolve()):
        where = "docs/src (the book)" if limit == BOOK else "the repository"
        return f"leaves {where}"
    if not dest.exists():
        return "no such file"
    if not anchor:
        return None
    if is_include:
        return None if anchor in include_anchors(dest) else f"no ANCHOR: {anchor} in {path_part}"
    if dest.is_dir() or dest.suffix != ".md":
        return f"an anchor on a file that is not markdown"
    return None if anchor in anchors(dest) else "no such heading"


def main():
    files = [ROOT / "README.md"] + sorted(BOOK.rglob("*.md"))
    broken, count = [], 0
    for source in files:
        text = source.read_text(encoding="utf-8")
        for number, line in prose_lines(text):
            targets = [(t, False) for t in INLINE.findall(line)]
            m = REFERENCE.match(line)
            if m:
                targets.append((m.group(1), False))
            targets += [(t, True) for t in INCLUDE.findall(line)]
            for target, is_include in targets:
                count += 1
                why = check_target(source, target, is_include)
                if why:
                    broken.append(f"{source.relative_to(ROOT)}:{number}: {target}: {why}")
    for b in broken:
        print(b)
    print(f"check-doc-links: {count} links in {len(files)} files, {len(broken)} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
