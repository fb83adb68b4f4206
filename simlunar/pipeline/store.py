"""The result folder: atomic writes and the per-unit cache.

Layout of ``<out>/``::

    config.yaml        the resolved experiment (defaults filled in, units as written)
    results.csv        tidy rows: unit, <sweep columns>, strategy, density, k, trial, metric, value
    scores.md          score tables (paper Tables 1 and 2 layout), Markdown
    scores.tex         the same tables, LaTeX (booktabs)
    provenance.json    versions, variant, git commit, seed, timings, cache hits
    units/<key>.json   one finished unit: rows, scores, timings (its existence marks completion)
    units/<key>.npz    the unit's arrays (image, depth, wavelet energy, plan, reconstruction)
    figures/           PNG and PDF

Every file is written to a temporary name in the same folder and moved into place with
``os.replace``, so a crash never leaves a half-written file under a final name. A unit's
``.npz`` is written before its ``.json``: a ``.json`` therefore always has its arrays.
"""

from __future__ import annotations

import csv
import io
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.atomic import atomic_write_bytes

UNITS_DIR = "units"


def atomic_write_text(path: str | Path, text: str) -> None:
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | Path, obj: Any) -> None:
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=True, allow_nan=True) + "\n")


def fmt_value(v: Any) -> str:
    """CSV text of a value: floats by ``repr`` (shortest round-trip), so files are exact."""
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v)).lower()
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if v is None:
        return ""
    if isinstance(v, (list, tuple, dict)):
        return json.dumps(v, sort_keys=True)
    return str(v)


def csv_text(rows: list[dict], columns: list[str]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([fmt_value(r.get(c)) for c in columns])
    return buf.getvalue()


def read_csv(path: str | Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def npz_bytes(arrays: dict[str, np.ndarray], *, level: int = 1) -> bytes:
    """An ``.npz`` archive (what ``np.load`` reads) deflated at zlib ``level``.

    ``np.savez_compressed`` always uses zlib's default level 6; on float rasters level 1
    compresses almost as well (within a few per cent) in about a quarter of the time, and the
    cache write sits on the runner's critical path once per unit.
    """
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=level) as zf:
        for name, value in arrays.items():
            with zf.open(f"{name}.npy", "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.asarray(value), allow_pickle=False)
    return buf.getvalue()


class UnitCache:
    """Finished units of a result folder, keyed by the hash of their resolved config."""

    def __init__(self, out_dir: str | Path):
        self.dir = Path(out_dir) / UNITS_DIR

    def json_path(self, key: str) -> Path:
        return self.dir / f"{key}.json"

    def npz_path(self, key: str) -> Path:
        return self.dir / f"{key}.npz"

    def has(self, key: str) -> bool:
        return self.json_path(key).is_file()

    def load(self, key: str) -> dict | None:
        """The cached record of ``key``, or None when absent or unreadable (then recomputed)."""
        try:
            rec = json.loads(self.json_path(key).read_text())
        except (OSError, ValueError):
            return None
        if rec.get("key") != key:
            return None
        return rec

    def load_arrays(self, key: str) -> dict[str, np.ndarray]:
        try:
            with np.load(self.npz_path(key), allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError):
            return {}

    def save(self, key: str, record: dict, arrays: dict[str, np.ndarray]) -> None:
        atomic_write_bytes(self.npz_path(key), npz_bytes(arrays))
        atomic_write_json(self.json_path(key), {**record, "key": key})
