"""probedyn.core: the registry pattern and the source's tables as presets (one place)."""

from __future__ import annotations

import ast
import math
import sys
import types
from dataclasses import dataclass
from pathlib import Path

import pytest

from probedyn.core.errors import ParameterError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import PRESETS, preset
from probedyn.core.registry import Model, Registry, RegistryError

ROOT = Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------ registry
class Law(Model):
    params = ParamSet([])

    def value(self):
        raise NotImplementedError


def _law(key="linear", **attrs):
    ns = dict(key=key, title="a law", source="eq 1", params=ParamSet([Param("a", 1.0, "N")]),
              value=lambda self: 1.0)
    ns.update(attrs)
    return type("L_" + key.replace("-", "_"), (Law,), ns)


def test_registry_finds_by_key_and_alias_and_suggests_the_closest():
    reg = Registry("law", Law, required=("value",), aliases={"straight": "linear"})
    cls = reg.register(_law())
    assert reg.get("Linear") is cls and reg.get("straight") is cls and "linear" in reg
    assert reg.create("linear").name == "linear" and reg.create("linear").equations == "eq 1"
    assert reg.table() == [{"key": "linear", "title": "a law", "source": "eq 1"}]
    with pytest.raises(ParameterError, match="did you mean 'linear'"):
        reg.get("lineer")
    reg.unregister("linear")
    assert reg.names() == []


def test_registry_with_a_family_parameter_type_serves_the_diagnose_causes():
    """Diagnose causes declare a tuple of CauseParam, not a ParamSet."""
    @dataclass(frozen=True)
    class CauseParam:
        name: str
        unit: str

    class Cause(Model):
        params: tuple = ()

        def effect(self, values, state):
            raise NotImplementedError

    reg = Registry("cause", Cause, required=("effect",), params_type=tuple)
    ok = type("Added", (Cause,), dict(key="added-mass", title="t", source="s",
                                      params=(CauseParam("dm", "kg"),), effect=lambda self, v, s: None))
    assert reg.register(ok) is ok
    with pytest.raises(RegistryError, match="'params'"):
        reg.register(type("Bad", (Cause,), dict(key="bad", title="t", source="s", params=ParamSet([]),
                                                effect=lambda self, v, s: None)))
    with pytest.raises(RegistryError, match="must define 'effect'"):
        reg.register(type("NoEffect", (Cause,), dict(key="none", title="t", source="s", params=())))


def test_registry_discovery_imports_the_package_and_retries_after_a_broken_module(tmp_path, monkeypatch):
    pkg = tmp_path / "lawpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "good.py").write_text(
        "from test_core import REG, _law\nREG.register(_law('good'))\n")
    (pkg / "broken.py").write_text("raise ImportError('a broken model module')\n")
    (pkg / "_private.py").write_text("raise RuntimeError('not imported: private')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(sys.modules, "test_core", sys.modules[__name__])
    global REG
    REG = Registry("law", Law, required=("value",), package="lawpkg")
    try:
        with pytest.raises(ImportError, match="broken"):
            REG.names()
        with pytest.raises(ImportError, match="broken"):  # not silently half-discovered
            REG.get("good")
        (pkg / "broken.py").write_text("")
        sys.modules.pop("lawpkg.broken", None)
        assert REG.names() == ["good"]
    finally:
        for m in [m for m in sys.modules if m.startswith("lawpkg")]:
            del sys.modules[m]


def test_registry_refuses_incomplete_or_conflicting_models():
    reg = Registry("law", Law, required=("value",), aliases={"straight": "linear"})
    reg.register(_law())
    for cls, match in [(_law("other", value=Law.value), "must define 'value'"),
                       (_law("other", source=""), "'source'"),
                       (_law("other", params={}), "'params'"),
                       (_law("straight"), "alias"),
                       (types.new_class("X"), "must derive from Law")]:
        with pytest.raises(RegistryError, match=match):
            reg.register(cls)
    twin = _law()
    twin.__qualname__ = "Twin"
    with pytest.raises(RegistryError, match="already taken"):
        reg.register(twin)


# ------------------------------------------------------------------ presets
def test_every_preset_value_has_a_unit_and_every_note_names_a_value():
    for key, p in PRESETS.items():
        assert p.key == key and p.source.startswith("Table")
        for name in p:
            assert name in p.units
        for name in p.notes:
            assert name == "*" or name in p, (key, name)
    with pytest.raises(ParameterError, match="did you mean 'table-2.1'"):
        preset("table-21")
    with pytest.raises(ParameterError, match="has no parameter"):
        preset("table-2.1")["lattice"]  # the mica lattice is Table 4.2's, typed once
    assert preset("table-2.1").pick("k_x", m="m_x") == {"k_x": preset("table-2.1")["k_x"],
                                                         "m": preset("table-2.1")["m_x"]}


#: literals equal to a table value that are not table values (checked by hand, with the reason)
NOT_TABLE_VALUES = {
    ("fem/materials.py", 1.65e-11): "PZT-5H data sheet s11; Tables 3.1/3.2 are corrected to it (departure 4)",
    ("schemes/ffm.py", 1.5e-07): "alpha sweep scan length 150 nm (Table 2.2's F_s = 1.5e-7 N is a force)",
    ("probedyn/diagnose/hydrodynamics.py", 0.33): "a thickness ratio t/w of the section-thickness table's grid "
                                                   "(Table 4.1's Poisson ratio 0.33 by coincidence)",
}


def test_no_table_constant_is_typed_outside_the_presets():
    """Every float literal of the package that equals a distinctive table value (two or more
    significant digits: 1.98e-18, 12.95e-9, 5.19e-10, ...) must come from core.presets."""
    distinctive: dict[float, list[str]] = {}
    for key, p in PRESETS.items():
        for name, v in p.data.items():
            if isinstance(v, float) and len(f"{abs(v):.6e}".split("e")[0].rstrip("0").replace(".", "")) >= 2:
                distinctive.setdefault(v, []).append(f"{key}:{name}")
    hits = []
    for top in ("probedyn", "meshes", "fem", "lumped", "schemes"):
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel == "probedyn/core/presets.py":
                continue
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Constant) and isinstance(node.value, float) and node.value != 0.0:
                    for v, where in distinctive.items():
                        if math.isclose(node.value, v, rel_tol=1e-12) and (rel, v) not in NOT_TABLE_VALUES:
                            hits.append(f"{rel}:{node.lineno} {node.value!r} is {', '.join(where)}")
    assert not hits, "table values typed outside probedyn.core.presets:\n" + "\n".join(hits)


def _openblas_threads(code: str, env_value: str | None) -> list[int]:
    """The thread counts of the OpenBLAS libraries loaded in a fresh interpreter after running ``code``."""
    import json
    import os
    import subprocess

    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if env_value is not None:
        env["OPENBLAS_NUM_THREADS"] = env_value
    probe = (code + "\nimport json\nfrom threadpoolctl import threadpool_info\n"
             "print(json.dumps([i['num_threads'] for i in threadpool_info() if i['internal_api'] == 'openblas']))")
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_openblas_is_held_to_one_thread_whichever_is_imported_first():
    """probedyn holds OpenBLAS to one thread (``probedyn/__init__.py``): through the environment where it is imported
    before numpy (the command line), and on the loaded libraries where numpy came first (a notebook's usual order;
    session 77 found such a session 20 % slower and rounding differently: the 6-mode modal example 1756 evaluations
    instead of 1852). A thread count the user set is left alone."""
    if not _openblas_threads("import numpy", "1"):
        pytest.skip("this numpy does not load OpenBLAS")
    assert _openblas_threads("import probedyn, numpy", None) == [1]
    assert _openblas_threads("import numpy, probedyn", None) == [1]
    mine = _openblas_threads("import numpy", "2")
    assert _openblas_threads("import numpy, probedyn", "2") == mine
