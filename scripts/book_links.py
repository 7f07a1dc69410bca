#!/usr/bin/env python3
"""mdBook preprocessor (docs/book.toml): links that leave docs/ resolve in the built book too.

The guide's Markdown is written for reading on GitHub, where `../ARCHITECTURE.md` from
docs/getting-started.md is the repository's ARCHITECTURE.md. The book is built from docs/ only,
so such a link would point outside it. docs/SUMMARY.md lists the repository pages the guide links
to (`../README.md`, `../ARCHITECTURE.md`, `../reports/paper/REPLICATION.md`); this preprocessor
gives them a place inside the book (`repository/PATH`, their path in the repository) and
rewrites every relative link of every chapter, resolved against the chapter's own place in the
repository:

- to a chapter of the book (a guide page or one of those repository pages): the chapter's path
  in the book, relative to the linking chapter (mdBook then turns `.md` into `.html`);
- to a file under docs/ that is not a chapter (an image): left as it is (mdBook copies it);
- to any other file of the repository (a CSV, a figure, a report's page): the link is dropped
  and the path is named instead, in code, since the book cannot serve it; an SVG or PNG image
  is embedded as a data: URI.

Code blocks and inline code are left alone. Protocol: `book_links.py supports RENDERER` exits 0;
otherwise it reads `[context, book]` as JSON on stdin and writes the book to stdout.
Python standard library only.
"""

from __future__ import annotations

import base64
import json
import posixpath
import re
import sys
from pathlib import Path

# Where a repository page outside docs/ lives in the book.
PREFIX = "repository/"


def repo_path_of(book_path: str) -> str:
    """A chapter's path in the repository, from its path in the book as SUMMARY.md names it."""
    return posixpath.normpath(posixpath.join("docs", book_path))


def book_path_of(repo_path: str) -> str:
    """Where a repository file lives in the book. A README.md becomes index.md, as mdBook's own
    `index` preprocessor (which runs after this one) would rename it."""
    book = repo_path[len("docs/"):] if repo_path.startswith("docs/") else PREFIX + repo_path
    head, name = posixpath.split(book)
    return posixpath.join(head, "index.md") if name.lower() == "readme.md" else book


def chapters(items: list) -> list[dict]:
    """Every chapter (dict with `content` and `path`) of the book's items, depth first."""
    out = []
    for item in items:
        if isinstance(item, dict) and "Chapter" in item:
            ch = item["Chapter"]
            out.append(ch)
            out.extend(chapters(ch.get("sub_items", [])))
    return out


def rewrite_target(target: str, here_repo: str, here_book: str, known: list[str], repo: Path):
    """The new target of a link from the chapter at `here_repo`, or None to drop the link."""
    first = known[0]
    if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith(("#", "/")) or not target:
        return target
    path, _, anchor = target.partition("#")
    resolved = posixpath.normpath(posixpath.join(posixpath.dirname(here_repo), path))
    frag = "#" + anchor if anchor else ""
    if resolved == "docs/SUMMARY.md":
        resolved, frag = first, ""  # the table of contents: the book's sidebar, its first page
    if resolved in known:
        rel = posixpath.relpath(book_path_of(resolved), posixpath.dirname(here_book) or ".")
        return rel + frag
    if resolved.startswith("docs/"):
        return target if here_repo.startswith("docs/") else None
    if not (repo / resolved).exists():
        return target  # a dead link: left for the link check to report
    return None


def embed(repo: Path, path: str) -> str | None:
    """An image of the repository as a data: URI."""
    kinds = {".svg": "image/svg+xml", ".png": "image/png"}
    kind = kinds.get(Path(path).suffix.lower())
    file = repo / path
    if kind is None or not file.is_file():
        return None
    return f"data:{kind};base64," + base64.b64encode(file.read_bytes()).decode("ascii")


LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\]]*\])*)\]\(([^()\s]+)((?:\s+\"[^\"]*\")?)\)")


def rewrite_line(line: str, here_repo: str, here_book: str, known: list[str], repo: Path) -> str:
    """Rewrite the links of one prose line (text inside backticks is left alone)."""
    # Split into code spans and prose, then rewrite the prose pieces only. A link whose text holds
    # inline code spans pieces; rejoin them for matching by masking the code first.
    masked, spans = [], []
    for k, piece in enumerate(re.split(r"(`+[^`]*`+)", line)):
        if k % 2:
            spans.append(piece)
            masked.append(f"\x00{len(spans) - 1}\x00")
        else:
            masked.append(piece)
    text = "".join(masked)

    def unmask(s: str) -> str:
        return re.sub(r"\x00(\d+)\x00", lambda m: spans[int(m.group(1))], s)

    def one(m: re.Match) -> str:
        bang, label, target, title = m.groups()
        new = rewrite_target(target, here_repo, here_book, known, repo)
        if new is not None:
            return f"{bang}[{label}]({new}{title})"
        path = posixpath.normpath(posixpath.join(posixpath.dirname(here_repo), target.partition("#")[0]))
        if bang:
            uri = embed(repo, path)
            return f"![{label}]({uri})" if uri else f"{label} (`{path}`)"
        return f"{label} (`{path}`)"

    return unmask(LINK.sub(one, text))


def rewrite(content: str, here_repo: str, here_book: str, known: list[str], repo: Path) -> str:
    out, fence = [], None
    for line in content.split("\n"):
        t = line.lstrip()
        m = re.match(r"(`{3,}|~{3,})", t)
        if fence is None and m:
            fence = m.group(1)
        elif fence is not None and t.startswith(fence) and not t[len(fence):].strip():
            fence = None
        elif fence is None:
            line = rewrite_line(line, here_repo, here_book, known, repo)
        out.append(line)
    return "\n".join(out)


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "supports":
        return 0
    context, book = json.load(sys.stdin)
    src = Path(context["root"]) / context["config"]["book"].get("src", "src")
    repo = src.resolve().parent
    items = book.get("items", book.get("sections", []))
    chs = [c for c in chapters(items) if c.get("path")]
    # Each chapter's place in the repository, and its new place in the book.
    places = []
    for ch in chs:
        here_repo = repo_path_of(ch["path"])
        places.append((ch, here_repo, book_path_of(here_repo)))
    known = [r for _, r, _ in places]  # in book order: the first is the opening page
    for ch, here_repo, here_book in places:
        ch["content"] = rewrite(ch["content"], here_repo, here_book, known, repo)
        ch["path"] = here_book
        if ch.get("source_path"):
            ch["source_path"] = here_book
    json.dump(book, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())
