"""Headless Chromium for the tests of the documentation site and the result reports.

Debian's ``chromium`` (``make browser`` installs it as root; CI runs as root). Outside CI a
machine without it, or a shell with an address-space limit (``ulimit -v``, under which
Chromium does not start), skips these tests, saying why; in CI (``CI=true``) they run.
"""

from __future__ import annotations

import html
import os
import re
import resource
import shutil
import subprocess
from pathlib import Path

import pytest

__all__ = ["chromium", "dump_dom", "images_load"]

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


def chromium() -> str:
    """The Chromium executable; skips the test (fails it in CI) when there is none."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    ci = os.environ.get("CI", "").lower() == "true"
    if not exe:
        msg = "chromium is not installed (`make browser` installs Debian's package as root)"
        if ci:
            pytest.fail(f"{msg}; CI must have it")
        pytest.skip(msg)
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft != resource.RLIM_INFINITY and not ci:
        # Chromium reserves far more address space than it uses and does not start under
        # `ulimit -v`; outside CI such a shell skips, in CI the run shows the failure
        pytest.skip(
            f"an address-space limit is set (ulimit -v {soft // 1024}): Chromium needs none"
        )
    return exe


def dump_dom(url: str, profile: Path, *, budget_ms: int = 5000, timeout_s: float = 120) -> str:
    """The DOM of ``url`` after ``budget_ms`` of virtual time (scripts run, images decoded)."""
    argv = [
        chromium(),
        *FLAGS,
        f"--user-data-dir={profile}",
        f"--virtual-time-budget={budget_ms}",
        "--dump-dom",
        url,
    ]
    r = subprocess.run(argv, capture_output=True, text=True, timeout=timeout_s, check=False)
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    hint = (
        f" (an address-space limit is set, ulimit -v {soft // 1024}: Chromium reserves more"
        " virtual memory than it uses and does not start under one)"
        if soft != resource.RLIM_INFINITY
        else ""
    )
    assert r.returncode == 0, f"chromium failed on {url}{hint}:\n{r.stderr[-2000:]}"
    return r.stdout


_PROBE = """<!DOCTYPE html><html><body><div id="imgs">{imgs}</div><pre id="result">pending</pre>
<script>
window.addEventListener("load", () => {{
  const imgs = [...document.querySelectorAll("#imgs img")];
  const ok = imgs.filter(i => i.complete && i.naturalWidth > 0);
  const bad = imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.dataset.src);
  document.getElementById("result").textContent =
    "loaded " + ok.length + " of " + imgs.length + (bad.length ? " missing " + bad.join(" ") : "");
}});
</script></body></html>
"""


def images_load(srcs: list[str], folder: Path, profile: Path) -> tuple[int, int, str]:
    """How many of the image ``srcs`` load and decode, resolved as a page in ``folder`` would
    resolve them: a probe page written there (and removed) holds one ``<img>`` per src and
    reports ``naturalWidth > 0`` after load. Returns (loaded, total, the probe's line)."""
    imgs = "".join(f'<img src="{html.escape(s)}" data-src="{html.escape(s[:80])}">' for s in srcs)
    probe = folder / "_image_probe.html"
    probe.write_text(_PROBE.format(imgs=imgs))
    try:
        dom = dump_dom(probe.as_uri(), profile)
    finally:
        probe.unlink(missing_ok=True)
    m = re.search(r'<pre id="result">loaded (\d+) of (\d+)([^<]*)</pre>', dom)
    assert m, f"the image probe did not report:\n{dom[-2000:]}"
    return int(m.group(1)), int(m.group(2)), m.group(0)
