#!/usr/bin/env python3
"""Link check of the built book and of README.md, without the network.

    python3 .ci/check_links.py [BOOK_DIR]     # BOOK_DIR defaults to docs/book

- The built book (`mdbook build docs` writes BOOK_DIR): every relative `href` and
  `src` of every page must name a file that exists, and every `#anchor` an `id` (or
  `name`) in the page it points to.
- README.md and crates/*/README.md, as GitHub shows them: every relative link and image target (outside code)
  must exist in the repository, and every `#anchor` into a markdown file must be the
  GitHub id of one of that file's headings.

External links (`https:`, `mailto:`, ...) are not fetched. Exits 1 listing every
broken link, 0 when there is none.
"""

from __future__ import annotations

import html.parser
import re
import sys
import unicodedata
from pathlib import Path
from urllib.parse import unquote, urlsplit

ROOT = Path(__file__).resolve().parent.parent


def is_external(target: str) -> bool:
    """A link with a scheme (`https:`, `mailto:`) or a network path (`//host`)."""
    return bool(re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target)) or target.startswith("//")


class Page(html.parser.HTMLParser):
    """The ids of one HTML page and the links it makes."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[tuple[int, str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if name == "id" or (tag == "a" and name == "name"):
                self.ids.add(value)
            if name in ("href", "src") and tag in ("a", "img", "link", "script", "source"):
                self.links.append((self.getpos()[0], value))


def parse_html(path: Path, cache: dict[Path, Page]) -> Page:
    if path not in cache:
        page = Page()
        page.feed(path.read_text(encoding="utf-8", errors="replace"))
        cache[path] = page
    return cache[path]


def check_book(book: Path) -> list[str]:
    errors: list[str] = []
    cache: dict[Path, Page] = {}
    pages = sorted(p for p in book.rglob("*.html"))
    if not pages:
        return [f"{book}: no HTML pages (was the book built?)"]
    for page_path in pages:
        # mdBook's 404 page uses links relative to the site root, not to itself.
        if page_path.name == "404.html":
            continue
        page = parse_html(page_path, cache)
        for line, link in page.links:
            if is_external(link) or link.startswith("javascript:"):
                continue
            parts = urlsplit(link)
            where = f"{page_path.relative_to(book)}:{line}: {link}"
            if parts.path:
                target = (page_path.parent / unquote(parts.path)).resolve()
                if target.is_dir():
                    target = target / "index.html"
                if not target.exists():
                    errors.append(f"{where}: no such file")
                    continue
            else:
                target = page_path
            if parts.fragment and target.suffix == ".html":
                if unquote(parts.fragment) not in parse_html(target, cache).ids:
                    errors.append(f"{where}: no anchor #{parts.fragment} in {target.name}")
    return errors


def strip_code(text: str) -> list[tuple[int, str]]:
    """The lines of a markdown file outside fenced code, inline code spans removed."""
    out: list[tuple[int, str]] = []
    fence: str | None = None
    for number, line in enumerate(text.split("\n"), start=1):
        stripped = line.lstrip()
        match = re.match(r"(`{3,}|~{3,})", stripped)
        if match:
            if fence is None:
                fence = match.group(1)[0] * len(match.group(1))
            elif stripped.startswith(fence):
                fence = None
            continue
        if fence is None:
            out.append((number, re.sub(r"`+[^`]*`+", "", line)))
    return out


def github_id(heading: str) -> str:
    """The id GitHub gives a heading: lower case, punctuation dropped, spaces to '-'."""
    text = re.sub(r"<[^>]+>", "", heading)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links keep their text
    text = text.replace("`", "").strip().lower()
    kept = []
    for ch in text:
        if ch in "-_" or ch.isalnum() or unicodedata.category(ch).startswith("M"):
            kept.append(ch)
        elif ch == " ":
            kept.append("-")
    return "".join(kept)


def markdown_ids(path: Path) -> set[str]:
    ids: set[str] = set()
    seen: dict[str, int] = {}
    fence: str | None = None
    for line in path.read_text(encoding="utf-8").split("\n"):
        stripped = line.lstrip()
        match = re.match(r"(`{3,}|~{3,})", stripped)
        if match:
            if fence is None:
                fence = match.group(1)[0] * len(match.group(1))
            elif stripped.startswith(fence):
                fence = None
            continue
        if fence is not None:
            continue
        heading = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if heading:
            base = github_id(heading.group(1))
            n = seen.get(base, 0)
            ids.add(base if n == 0 else f"{base}-{n}")
            seen[base] = n + 1
    return ids


LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HTML_TARGET = re.compile(r"""<(?:img|a|source)\b[^>]*\b(?:src|href)=["']([^"']+)["']""")


def check_markdown(path: Path) -> list[str]:
    errors: list[str] = []
    text = path.read_text(encoding="utf-8")
    for number, line in strip_code(text):
        for target in LINK.findall(line) + HTML_TARGET.findall(line):
            if is_external(target):
                continue
            parts = urlsplit(target)
            where = f"{path.relative_to(ROOT)}:{number}: {target}"
            if parts.path:
                resolved = (path.parent / unquote(parts.path)).resolve()
                if not resolved.exists():
                    errors.append(f"{where}: no such file")
                    continue
            else:
                resolved = path
            if parts.fragment:
                if resolved.suffix != ".md":
                    errors.append(f"{where}: an anchor into a file that is not markdown")
                elif unquote(parts.fragment) not in markdown_ids(resolved):
                    errors.append(f"{where}: no heading with the id #{parts.fragment}")
    return errors


def main() -> int:
    book = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "book"
    readmes = [ROOT / "README.md", *sorted(ROOT.glob("crates/*/README.md"))]
    errors = check_book(book.resolve())
    for readme in readmes:
        errors += check_markdown(readme)
    for error in errors:
        print(f"broken link: {error}", file=sys.stderr)
    pages = sum(1 for _ in book.rglob("*.html")) if book.exists() else 0
    print(f"links: {pages} book pages and {len(readmes)} READMEs checked, {len(errors)} broken")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
