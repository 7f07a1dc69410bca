#!/usr/bin/env python3
"""Check the built book (`mdbook build docs`, in target/book): nothing points nowhere.

    scripts/check_book.py [BOOK_DIR]     # default: target/book

Every relative `href` and `src` of every HTML page must name a file of the built book, and every
`#fragment` an `id` (or `name`) of the page it points to. Web links (`http…`, `mailto:`, …) and
data: URIs are not checked. A page with `<base href>` (mdBook's 404.html) resolves against it.
Also checks that every ```rust block of docs/library.md is, line for line, part of a file under
examples/ (so the page shows the code that `cargo test` compiles). Exit 1 with one line per
problem; Python standard library only.
"""

from __future__ import annotations

import posixpath
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

REPO = Path(__file__).resolve().parent.parent


class Page(HTMLParser):
    """The ids, the links and the `<base href>` of one HTML page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.base: str | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key) and (key == "id" or tag == "a"):
                self.ids.add(a[key] or "")
        if tag == "base" and a.get("href"):
            self.base = a["href"]
        for key in ("href", "src"):
            if a.get(key) is not None and tag in ("a", "link", "img", "script", "iframe", "source"):
                self.links.append(a[key] or "")


def parse(path: Path) -> Page:
    p = Page()
    p.feed(path.read_text(encoding="utf-8", errors="replace"))
    return p


def check_links(book: Path) -> list[str]:
    pages = {p.relative_to(book).as_posix(): parse(p) for p in sorted(book.rglob("*.html"))}
    problems = []
    for name, page in pages.items():
        for link in page.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith("//") or not link:
                continue
            base_dir = posixpath.dirname(name)
            if page.base is not None and page.base.startswith("/"):
                base_dir = page.base.strip("/")
            if parts.path.startswith("/"):
                continue  # site-absolute: depends on where the book is served
            target = posixpath.normpath(posixpath.join(base_dir, unquote(parts.path))) if parts.path else name
            if target.startswith(".."):
                problems.append(f"{name}: {link}: leaves the book")
                continue
            file = book / target
            if file.is_dir():
                target = posixpath.join(target, "index.html")
                file = book / target
            if not file.is_file():
                problems.append(f"{name}: {link}: {target} does not exist")
                continue
            if parts.fragment and target.endswith(".html"):
                ids = pages[target].ids if target in pages else parse(file).ids
                if unquote(parts.fragment) not in ids:
                    problems.append(f"{name}: {link}: {target} has no id {parts.fragment!r}")
    return problems


def fenced_rust(text: str) -> list[tuple[int, list[str]]]:
    out, lines, i = [], text.split("\n"), 0
    while i < len(lines):
        if lines[i].strip() == "```rust":
            start, body = i + 2, []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                body.append(lines[i])
                i += 1
            out.append((start, body))
        i += 1
    return out


def check_snippets() -> list[str]:
    page = REPO / "docs" / "library.md"
    sources = {p: p.read_text(encoding="utf-8").split("\n") for p in sorted((REPO / "examples").glob("*.rs"))}
    problems = []
    for line, body in fenced_rust(page.read_text(encoding="utf-8")):
        n = len(body)
        if not any(src[k : k + n] == body for src in sources.values() for k in range(len(src) - n + 1)):
            problems.append(f"docs/library.md:{line}: this ```rust block is not part of any file in examples/")
    return problems


def main() -> int:
    book = Path(sys.argv[1]) if len(sys.argv) > 1 else REPO / "target" / "book"
    if not (book / "index.html").is_file():
        print(f"{book}: no built book (run `mdbook build docs` first)", file=sys.stderr)
        return 1
    problems = check_links(book) + check_snippets()
    for p in problems:
        print(p, file=sys.stderr)
    n = sum(1 for _ in book.rglob("*.html"))
    print(f"check_book: {n} pages, {len(problems)} problems", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
