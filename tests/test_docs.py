"""docs/algorithms.md and docs/design.md have every section the code cites.

The code cites ``docs/algorithms.md §<n>`` (or algorithms.md) and
``docs/design.md "<title>"`` (or design.md); each must name a heading of the
repository's own document, so that no citation points at nothing.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("core", "app", "api_schemas", "evaluation", "bench", "tests")
SECTION = re.compile(r"(?i)algorithms\.md[`]?\s+§\s*(\d+(?:\.\d+)?)")
TITLE = re.compile(r'(?i)design\.md[`]?\s+"([^"]+)"')


def cited(pattern: re.Pattern[str]) -> set[str]:
    found: set[str] = set()
    for package in SOURCES:
        for path in (ROOT / package).rglob("*.py"):
            if path == Path(__file__).resolve():
                continue  # its docstring shows the forms, it cites nothing
            text = " ".join(path.read_text(encoding="utf-8").split())  # citations wrap lines
            found.update(match.group(1) for match in pattern.finditer(text))
    return found


def headings(name: str) -> list[str]:
    text = (ROOT / "docs" / name).read_text(encoding="utf-8")
    return [line.lstrip("#").strip() for line in text.splitlines() if line.startswith("#")]


def test_every_cited_algorithms_section_exists() -> None:
    numbers = {title.split()[0].rstrip(".") for title in headings("algorithms.md")}
    sections = cited(SECTION)
    assert {"1.1", "3.3", "4", "6.4"} <= sections  # the scan finds the citations
    assert sections <= numbers, sorted(sections - numbers)


def test_every_cited_design_section_exists() -> None:
    titles = headings("design.md")
    for title in cited(TITLE):
        assert any(heading.startswith(title) for heading in titles), title
    assert "The session engine" in titles and "Session config" in titles


def test_algorithms_has_a_bibliography_with_the_four_papers() -> None:
    text = (ROOT / "docs" / "algorithms.md").read_text(encoding="utf-8")
    bibliography = text.split("## Bibliography", 1)[1]
    for key in ("[T2T]", "[MTT]", "[DH]", "[HZ]"):
        assert f"**{key}**" in bibliography, key
    assert "10.1016/j.inffus.2014.01.007" in bibliography
