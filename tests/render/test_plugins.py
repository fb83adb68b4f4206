"""The plugin package: one module per Mitsuba plugin, each documenting its parameters.

The parameter table in each module's docstring is parsed and checked against the plugin
itself: every parameter ``mi.traverse`` exposes is documented, and loading the plugin with
the documented defaults spelled out gives the same BSDF as loading it with none.
"""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

from simlunar.render.plugins import PLUGINS

_ROW = re.compile(r"^``(\w+)``\s+(.+)$")


def parameter_table(module) -> dict[str, dict[str, str]]:
    """name -> {type, default, unit} from the module docstring's table."""
    rows = {}
    lines = module.__doc__.splitlines()
    borders = [i for i, line in enumerate(lines) if line.startswith("====")]
    assert len(borders) == 3, "a parameter table: border, header, border, rows, border"
    for line in lines[borders[1] + 1 : borders[2]]:
        m = _ROW.match(line)
        if not m:
            continue
        cols = re.split(r"\s{2,}", m.group(2))
        rows[m.group(1)] = {"type": cols[0], "default": cols[1].strip("`"), "unit": cols[2]}
    return rows


def _value(row):
    if row["type"] == "string":
        return row["default"]
    return float(row["default"])


def _eval(mi, bsdf):
    import drjit as dr

    t = np.radians(np.arange(5, 90, 20))
    ti, to, dp = (a.ravel() for a in np.meshgrid(t, t, np.radians([0, 90, 180]), indexing="ij"))
    wi = np.stack([np.sin(ti), 0 * ti, np.cos(ti)])
    wo = np.stack([np.sin(to) * np.cos(dp), np.sin(to) * np.sin(dp), np.cos(to)])
    si = dr.zeros(mi.SurfaceInteraction3f, len(ti))
    si.wi = mi.Vector3f(wi.astype(np.float32))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    return np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wo.astype(np.float32))))


def test_every_plugin_module_has_a_parameter_table_with_type_default_unit():
    assert set(PLUGINS) >= {"oren_nayar", "hapke", "lunar_lambert"}
    for name, module in PLUGINS.items():
        assert module.NAME == name
        table = parameter_table(module)
        assert "reflectance" in table, name
        for param, row in table.items():
            assert row["type"] in ("float", "float or texture", "string"), (name, param)
            assert row["unit"] in ("1", "radian", "--"), (name, param)
            _value(row)  # a default that parses


@pytest.mark.parametrize("name", sorted(PLUGINS))
def test_documented_parameters_are_the_plugins_and_defaults_are_true(mi, name):
    table = parameter_table(PLUGINS[name])
    implicit = mi.load_dict({"type": name})
    # what traverse exposes is documented
    assert set(mi.traverse(implicit).keys()) <= {f"{p}.value" for p in table} | set(table)
    explicit = mi.load_dict({"type": name, **{p: _value(r) for p, r in table.items()}})
    a, b = _eval(mi, implicit), _eval(mi, explicit)
    assert np.abs(a).max() > 0
    # defaults are printed to 5 significant digits (theta_bar 0.41289 rad)
    np.testing.assert_allclose(b, a, rtol=2e-5)
    # ... which is tight enough to catch a default 5% + 0.05 off: 10x that tolerance at least
    # (a parameter that acts only once another leaves its default is checked with that set)
    for p, r in table.items():
        if r["type"] != "string":
            context = {"type": name, **_ACTIVE_WITH.get((name, p), {})}
            base = _eval(mi, mi.load_dict(context))
            lit = base > 0
            off = mi.load_dict({**context, p: _value(r) * 1.05 + 0.05})
            rel = np.abs(_eval(mi, off) - base)[lit] / base[lit]
            assert rel.max() > 10 * 2e-5, p


#: (plugin, parameter) -> the other parameters under which it acts (at their defaults it has
#: no effect: Hapke's coherent-backscatter width needs a surge amplitude)
_ACTIVE_WITH = {("hapke", "h_C"): {"B_C0": 0.5}}


def test_a_gated_parameter_has_no_effect_at_its_gates_defaults(mi):
    for (name, p), gate in _ACTIVE_WITH.items():
        row = parameter_table(PLUGINS[name])[p]
        a = _eval(mi, mi.load_dict({"type": name}))
        b = _eval(mi, mi.load_dict({"type": name, p: _value(row) * 1.05 + 0.05}))
        np.testing.assert_array_equal(a, b)
        assert set(gate) <= set(parameter_table(PLUGINS[name]))


def test_the_plugins_are_those_the_bsdf_registry_names():
    # PLUGINS comes from the package's modules; the BSDF registry names its plugin modules
    # apart: the two lists must agree (a BSDF whose plugin lives elsewhere would be missed)
    from simlunar.render.materials import BSDFS

    named = {n: e.meta["plugin"] for n, e in BSDFS.items() if e.meta.get("plugin")}
    assert named == {n: m.__name__ for n, m in PLUGINS.items()}


def test_importing_the_plugins_does_not_import_mitsuba():
    code = (
        "import sys, simlunar.render.plugins, simlunar.render.bsdfs; "
        "assert 'mitsuba' not in sys.modules and 'drjit' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_plugins_are_registered_once_the_variant_is_set(mi):
    for name in PLUGINS:
        assert type(mi.load_dict({"type": name})).__name__.lower().startswith(name.split("_")[0])
