"""Write the vendored extract of recorded flights (``evaluation/data/``) from the ``traffic`` wheel.

The real-traffic scene (:mod:`evaluation.traffic`) replays flights recorded
by ADS-B receivers around Paris on 7 October 2021: the ``quickstart``
collection of the ``traffic`` package's sample data (X. Olive, MIT licence;
``evaluation/data/LICENSE-traffic``). The package itself is not a
dependency (it brings pyarrow, onnxruntime and a dozen more); its wheel is a
zip, and this script reads the one JSON file it needs from it::

    pip download traffic==2.13 --no-deps -d /tmp/traffic
    .venv/bin/python -m evaluation.traffic_extract /tmp/traffic/traffic-2.13-py3-none-any.whl

The extract is the :data:`WINDOW` (30 minutes, plus a minute on each side for
the smoothing) of the :data:`FLIGHTS` (the 20 aircraft longest airborne in
it), every record as it was recorded: time (s from the window's start),
ICAO address, callsign, latitude, longitude (degrees), barometric altitude
(feet) — nothing cleaned: :func:`evaluation.traffic.load_flights` drops the
glitches and smooths.
"""

from __future__ import annotations

import csv
import gzip
import io
import json
import sys
import zipfile
from pathlib import Path

SAMPLE = "traffic/data/samples/collections/quickstart.json.gz"
EXTRACT = Path(__file__).resolve().parent / "data" / "quickstart-paris-20.csv.gz"
WINDOW_START_MS = 1_633_612_801_000
"""2021-10-07 13:20:01 UTC: the collection's first record + 4800 s."""
WINDOW = (-60.0, 1860.0)
"""Seconds around the window's start that the extract keeps (30 min and a margin)."""
FLIGHTS = [
    "FHMAC",
    "AFR15AH",
    "DITRA",
    "AFR1285",
    "AFR17YC",
    "AFR1013",
    "RYR43ZU",
    "VLJ670W",
    "CCM774V",
    "DCARO",
    "AFR54JE",
    "VLG8018",
    "VLG76Y",
    "AFR73VJ",
    "TAP442",
    "AFR474",
    "MTO787",
    "TVF19YP",
    "VLJ432T",
    "TVF44YH",
]
COLUMNS = ("t", "icao24", "callsign", "lat", "lon", "alt_ft")


def extract(wheel: Path, out: Path = EXTRACT) -> int:
    """Write the extract from the wheel's sample; returns the number of records."""
    with zipfile.ZipFile(wheel) as archive:
        records = json.loads(gzip.decompress(archive.read(SAMPLE)))
    rows = []
    for record in records:
        t = (record["timestamp"] - WINDOW_START_MS) / 1000.0
        if not (WINDOW[0] <= t <= WINDOW[1]) or record.get("callsign") not in FLIGHTS:
            continue
        if record.get("onground") or None in (
            record.get("latitude"),
            record.get("longitude"),
            record.get("altitude"),
        ):
            continue
        rows.append(
            (
                f"{t:.0f}",
                record["icao24"],
                record["callsign"],
                f"{record['latitude']:.6f}",
                f"{record['longitude']:.6f}",
                f"{record['altitude']:.0f}",
            )
        )
    rows.sort(key=lambda row: (row[2], float(row[0])))
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(COLUMNS)
    writer.writerows(rows)
    out.write_bytes(gzip.compress(text.getvalue().encode(), mtime=0))
    return len(rows)


if __name__ == "__main__":
    print(f"{extract(Path(sys.argv[1]))} records written to {EXTRACT}")
