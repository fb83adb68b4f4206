"""What ``simlunar run --dry-run`` says: the units a run would compute, and a rough estimate
of its time and peak memory, with nothing written.

The estimate is a cost model calibrated on runs on the 2-core development machine
(``--workers 1`` unless said; load 2-5):

* per unit: terrain ``0.2 s + 2 us`` per cell; render (and, with figures, the sparse-mesh
  render) ``2.2 s + 0.2 us`` per pixel-sample, the fixed part being the JIT's start
  (quickstart and ablation_light: 2.3-2.8 s per render);
* sampling study: ``12 ms + 0.1 us`` per cell for each (strategy, density, trial) of the
  paper's one-shot strategies (ablation_light: 250 tasks on 100 000 cells in 5.4 s; the
  five-strategy table1_aerial at full size, 1.6 M cells: 15 units of 1100 tasks in 23.4 min
  with 2 workers), three times that for the Lloyd layouts (``lloyd_uniform``, any
  ``placement: lloyd``), multi-round (``sequential``) and the oracles (quickstart: its 84 such
  tasks took 3.7 s of its 5.2 s study);
* a start-up of 4 s (imports) per run; units run ``workers`` at a time.
* memory: 0.38 GB (the process with the scientific stack and Mitsuba) + 0.06 GB with
  figures + 600 bytes per terrain cell per unit in flight (measured peaks 0.39 and 0.43 GB).

Scanner and LIDAR studies have no time model here (their cost is frames and beams, see the
run times in docs/experiments.md); their units and memory are still reported. Read the time
as a factor-of-three estimate: the load of a shared machine alone moves it by 2x.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline import preflight
from simlunar.pipeline.runner import expand
from simlunar.results.records import unit_label
from simlunar.results.store import UnitCache

__all__ = ["RunEstimate", "estimate_run"]

START_S = 4.0
TERRAIN_S, TERRAIN_S_PER_CELL = 0.2, 2e-6
RENDER_S, RENDER_S_PER_SAMPLE = 2.2, 2e-7
TASK_S, TASK_S_PER_CELL = 0.012, 1e-7
HEAVY_FACTOR = 3.0
BASE_BYTES, FIGURE_BYTES, BYTES_PER_CELL = 0.38e9, 0.06e9, 600.0


@dataclass(frozen=True)
class RunEstimate:
    """A run's units and its estimated cost.

    Attributes
    ----------
    units : list of str
        One label per work unit (its sweep point), in order.
    cached : int
        Units already finished in the result folder (computed again: none).
    seconds : float or None
        Estimated wall time of the units still to compute, s (None: no time model for
        the study kind).
    peak_bytes : float
        Estimated peak resident memory, bytes.
    """

    units: list[str]
    cached: int
    seconds: float | None
    peak_bytes: float

    def lines(self, out_dir: Path) -> list[str]:
        """What ``--dry-run`` prints."""
        n = len(self.units)
        out = [f"dry run: nothing written; results would go to {out_dir}"]
        out.append(
            f"work units: {n} ({self.cached} already in the folder, {n - self.cached} to compute)"
        )
        out += [f"  unit {i}: {label}" for i, label in enumerate(self.units)]
        if self.seconds is None:
            out.append(
                "estimated time: no time model for this study kind (see docs/experiments.md)"
            )
        else:
            out.append(
                f"estimated time: {_duration(self.seconds)} (rough, within about 3x; calibrated "
                "on 2 cores)"
            )
        out.append(f"estimated peak memory: {self.peak_bytes / 1e9:.2f} GB")
        return out


def _duration(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"


def _heavy(name: str, study) -> bool:
    opts = (getattr(study, "strategy_options", None) or {}).get(name)
    base = getattr(opts, "strategy", None) or name
    lloyd = getattr(opts, "placement", None) == "lloyd"
    return lloyd or base == "lloyd_uniform" or base == "sequential" or base.startswith("oracle")


def _unit_seconds(cfg: ExperimentCfg, cells: int, pixels: int, figures: bool) -> float | None:
    study = cfg.study
    if getattr(study, "kind", "sampling") != "sampling":
        return None
    samples = pixels * cfg.render.spp
    render = RENDER_S + RENDER_S_PER_SAMPLE * samples
    weight = sum(HEAVY_FACTOR if _heavy(s, study) else 1.0 for s in study.strategies)
    tasks = weight * len(study.densities) * study.trials  # a unit is one terrain seed
    terrain = TERRAIN_S + TERRAIN_S_PER_CELL * cells
    return terrain + render * (2 if figures else 1) + tasks * (TASK_S + TASK_S_PER_CELL * cells)


def estimate_run(
    cfg: ExperimentCfg, out_dir: str | Path, *, workers: int = 1, figures: bool = True
) -> RunEstimate:
    """The units of ``cfg`` and the estimated cost of running them into ``out_dir``.

    Runs every check ``simlunar run`` makes before computing (inputs, geometry, study sizes)
    and reads the folder's unit cache; writes nothing.

    Raises
    ------
    simlunar.errors.ConfigError
        What ``simlunar run`` would stop at.
    """
    units = expand(cfg)
    checks = preflight.check_units(units)
    done = UnitCache(out_dir).keys()
    todo_s: list[float] = []
    timed = True
    peak = 0.0
    for u, f in zip(units, checks.terrain):
        ucfg = ExperimentCfg.model_validate(u.config)
        cells = f.rows * f.cols
        rows, cols = preflight.image_shape(ucfg.render, f)
        peak = max(peak, BYTES_PER_CELL * cells)
        if u.key in done:
            continue
        s = _unit_seconds(ucfg, cells, rows * cols, figures)
        if s is None:
            timed = False
        else:
            todo_s.append(s)
    workers = max(1, int(workers or 1))
    seconds = None
    if timed:
        seconds = START_S + sum(todo_s) / min(workers, max(1, len(todo_s)))
    peak_bytes = BASE_BYTES + (FIGURE_BYTES if figures else 0.0) + peak * min(workers, len(units))
    return RunEstimate(
        units=[unit_label(u) for u in units],
        cached=sum(u.key in done for u in units),
        seconds=seconds,
        peak_bytes=peak_bytes,
    )
