"""Each ``reproduce`` target runs end to end on a reduced size and writes its PNG."""

from __future__ import annotations

from pathlib import Path

import pytest

from core.errors import InvalidInput
from evaluation.catalogue import CATALOGUE
from evaluation.figures import DRAWINGS, FIGURES, main, reproduce

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_reproduce_writes_a_png(name: str, tmp_path: Path) -> None:
    lines: list[str] = []
    path = reproduce(name, tmp_path / "figures", reduced=True, echo=lines.append)
    assert path == tmp_path / "figures" / f"{name}.png"
    content = path.read_bytes()
    assert content.startswith(PNG_MAGIC)
    assert len(content) > 20_000
    assert any("seed" in line for line in lines)  # every run says its seeds
    assert lines[-1] == f"wrote {path}"
    numbers = (tmp_path / "figures" / f"{name}.txt").read_text()
    echoed = "\n".join(lines[:-2])  # all but the time taken and the file written
    assert numbers == f"$ credal-fusion reproduce {name} --reduced\n{echoed}\n"


def test_the_registry_names_the_papers_figures() -> None:
    assert set(FIGURES) == {
        "t2t-four",
        "t2t-two-class",
        "aircraft",
        "pedestrian",
        "unit-study",
        "close-pair",
        "crossing",
        "road-four",
        "accelerating",
        "overtaking",
        "mtt-scenes",
        "hz-scale",
        "peers",
        "real-traffic",
    }
    assert all(spec.name == name and spec.paper for name, spec in FIGURES.items())
    assert set(DRAWINGS) == set(CATALOGUE) == set(FIGURES)  # a drawing for every name


def test_unknown_figures_are_refused(tmp_path: Path) -> None:
    with pytest.raises(InvalidInput, match="unknown figure"):
        reproduce("fig-99", tmp_path)
    with pytest.raises(SystemExit):
        main(["fig-99", "--out", str(tmp_path)])


def test_module_entry_point(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["pedestrian", "--reduced", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "pedestrian.png").exists()
    assert "seed 0" in capsys.readouterr().out
