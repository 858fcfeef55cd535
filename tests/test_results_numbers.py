"""docs/RESULTS.md quotes only numbers its figures' numbers files contain.

Every interval RESULTS quotes — ``estimate [low, high]``, or ``k/n [low,
high]`` for a share of runs — must be written, to the digits quoted, in the
numbers file of the run that drew the figure (``docs/figures/NAME.txt``):
the file of the section's figure when the section names one (``## `NAME` …``
or a section mapped below), any numbers file otherwise. A number rounded
for the page matches when it is the file's number rounded to the quoted
digits; a percentage interval (``5 % [1, 24]``) matches the file's shares
× 100. A re-run that changes a number without RESULTS following fails here.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "RESULTS.md"
FIGURES = ROOT / "docs" / "figures"

NUMBER = r"−?-?\d+(?:\.\d+)?(?:·10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+|e-?\d+)?"
UNIT = r"(?:\*\*)?(?:\s*(?P<percent>%)|\s*(?:m/s|m²|m|s|steps?|runs?|realisations?))?(?:\*\*)?"
QUOTED = re.compile(
    rf"(?P<estimate>\d+/\d+|{NUMBER}){UNIT}\s*\[(?P<low>{NUMBER}),\s*(?P<high>{NUMBER})\]"
)
"""An estimate (or k/n runs), an optional unit, its interval; a bare range is not a quote."""
FILED = re.compile(
    rf"(?P<estimate>\d+/\d+|{NUMBER})?\s*\[(?P<low>{NUMBER}),\s*(?P<high>{NUMBER})\]"
)
SECTIONS = {"Unit study": "unit-study"}
"""Headings that name their figure in words rather than as ``NAME``."""
SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def value(text: str) -> tuple[float, int]:
    """The number and its decimals (its last quoted digit's place)."""
    text = text.replace("−", "-")
    if "·10" in text:
        mantissa, exponent = text.split("·10")
        return float(mantissa) * 10 ** int(exponent.translate(SUPERSCRIPT)), 99
    if "e" in text:
        return float(text), 99
    decimals = len(text.split(".")[1]) if "." in text else 0
    return float(text), decimals


def matches(quoted: str, filed: float, scale: float = 1.0) -> bool:
    number, decimals = value(quoted)
    filed *= scale
    if decimals == 99:
        return abs(filed - number) <= 0.051 * abs(number) + 1e-300
    return abs(filed - number) <= 0.5 * 10.0**-decimals + 1e-9


def filed_intervals(names: list[str]) -> list[tuple[float | None, float, float]]:
    found = []
    for name in names:
        text = (FIGURES / f"{name}.txt").read_text(encoding="utf-8")
        for match in FILED.finditer(text):
            estimate = match.group("estimate")
            if estimate is not None and "/" in estimate:
                hits, runs = (int(part) for part in estimate.split("/"))
                mean: float | None = hits / runs if runs else None
            else:
                mean = None if estimate is None else value(estimate)[0]
            found.append(
                (
                    mean,
                    value(match.group("low"))[0],
                    value(match.group("high"))[0],
                )
            )
    return found


def sections() -> list[tuple[str, list[str], str]]:
    """(heading, numbers files it may quote, text) for every ``##`` section."""
    every = sorted(path.stem for path in FIGURES.glob("*.txt"))
    found = []
    for block in RESULTS.read_text(encoding="utf-8").split("\n## ")[1:]:
        heading, _, text = block.partition("\n")
        named = re.match(r"`([a-z0-9-]+)`", heading)
        name = named.group(1) if named else SECTIONS.get(heading.split(":")[0].strip())
        files = [name] if name in every else every
        found.append((heading, files, text))
    return found


def quoted_intervals(text: str) -> list[re.Match[str]]:
    # links and figure file names are not numbers; code spans may hold seeds
    text = re.sub(r"\]\([^)]*\)", "]", re.sub(r"`[^`]*`", "", text))
    return list(QUOTED.finditer(text))


def test_results_quotes_intervals() -> None:
    count = sum(len(quoted_intervals(text)) for _, _, text in sections())
    assert count >= 20  # "every number a verdict rests on carries its interval"


@pytest.mark.parametrize(("heading", "files", "text"), sections(), ids=lambda x: str(x)[:30])
def test_every_quoted_interval_is_in_its_numbers_file(
    heading: str, files: list[str], text: str
) -> None:
    filed = filed_intervals(files)
    missing = []
    for match in quoted_intervals(text):
        scale = 100.0 if match.group("percent") else 1.0
        estimate = match.group("estimate")
        fraction = None
        if "/" in estimate:
            hits, runs = (int(part) for part in estimate.split("/"))
            fraction = hits / runs
        found = any(
            matches(match.group("low"), low, scale)
            and matches(match.group("high"), high, scale)
            and mean is not None
            and (
                abs(mean - fraction) < 1e-9
                if fraction is not None
                else matches(estimate, mean, scale)
            )
            for mean, low, high in filed
        )
        if not found:
            missing.append(match.group(0))
    assert not missing, f"{heading}: not in {files}: {missing}"
