"""``simlunar`` whose work units are :func:`fake_unit.fake_unit` (fault tests in subprocesses).

Everything else is the real CLI: validation, preflight, folder lock, runner, exit codes.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fake_unit import fake_unit

from simlunar.pipeline import runner

runner.run_experiment.__kwdefaults__["compute"] = fake_unit

if __name__ == "__main__":
    from simlunar.cli import main

    main()
