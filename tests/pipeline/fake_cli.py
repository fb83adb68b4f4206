"""``simlunar`` whose work units are :func:`fake_unit.fake_unit` (fault tests in subprocesses),
or with ``SIMLUNAR_TEST_REAL_UNITS`` set the real units behind :func:`fake_unit.enter_unit`.

Everything else is the real CLI: validation, preflight, folder lock, runner, exit codes.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

# the checkout these tests belong to, ahead of any installed simlunar: run as a script, only this
# folder is on sys.path, and an editable install made from another checkout (a git worktree
# sharing one virtual environment) would run that checkout's code in the subprocess
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from fake_unit import fake_unit

from simlunar.pipeline import runner

if os.environ.get("SIMLUNAR_TEST_REAL_UNITS"):  # the real units, behind the test gate
    from fake_unit import gated

    from simlunar.pipeline.unit import compute_unit

    runner.run_experiment.__kwdefaults__["compute"] = gated(compute_unit)
elif os.environ.get("SIMLUNAR_TEST_POOL_UNITS"):  # the real sampling study, no render
    from fake_unit import pool_unit

    runner.run_experiment.__kwdefaults__["compute"] = pool_unit
else:
    runner.run_experiment.__kwdefaults__["compute"] = fake_unit

if __name__ == "__main__":
    import signal

    # Ctrl-C as in a terminal, whatever the disposition the test process passed down (a
    # child started with SIGINT ignored would never see the tests' SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    from simlunar.cli import main

    main()
