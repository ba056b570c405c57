"""Adding a model is one file (docs/developing.md, "one registry pattern").

``tests/model_coulomb.py`` (a friction law), ``tests/model_hertz.py`` (a contact law) and
``tests/cause_interference.py`` (a diagnose cause) are written the way a user adds a model: one
module that declares the class and registers it. Here
they run through the command line in-process, and their physics is checked against closed
forms; a class missing a required piece is refused when it registers.
"""

from __future__ import annotations

import importlib
import json
import math

import numpy as np
import pytest
from numba import njit

from probedyn.cli import main
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.core.registry import RegistryError
from probedyn.probes import PROBES, Probe
from probedyn.schemes.contact.base import CONTACT_MODELS, ContactModel
from probedyn.schemes.friction.base import FRICTION_MODELS, FrictionModel

# the package's own models, before any example file registers one (a snapshot, not a second list)
BUILTIN_FRICTION = frozenset(FRICTION_MODELS.names())
BUILTIN_CONTACT = frozenset(CONTACT_MODELS.names())

T21 = preset("table-2.1")


def _one_file_model(module: str, cls_name: str, registry):
    """Import the model's file (which registers it) and take it out again afterwards, so the
    other tests see the built-in registries only."""
    cls = getattr(importlib.import_module(module), cls_name)
    registry.register(cls)  # again, if an earlier test took it out (same class: idempotent)
    return cls


@pytest.fixture
def coulomb():
    yield _one_file_model("model_coulomb", "Coulomb", FRICTION_MODELS)
    FRICTION_MODELS.unregister("coulomb")


@pytest.fixture
def hertz():
    yield _one_file_model("model_hertz", "Hertz", CONTACT_MODELS)
    CONTACT_MODELS.unregister("hertz")


def test_a_friction_model_in_one_file_runs_through_simulate_ffm(coulomb, capsys):
    """Coulomb friction F_0 tanh(v/v_0) in the FFM model (2.13), (2.15): the spring loads up to
    F_0 (travel F_0/k_x), then the tip slides and the lateral force k_x (V t - x) stays at the
    plateau F_0 tanh(V/v_0) = F_0 (V/v_0 = 2000). The transient after the onset of sliding decays
    with c_x/k_x = 35 ns, far below the 25 ms of sliding scanned; the integrator's tolerances
    (rtol 1e-5 on x ~ 3 F_0/k_x) bound the plateau's error by ~3e-5 of F_0: tolerance 1e-4."""
    F0, k = 5e-9, T21["k_x"]
    L = 3 * F0 / k
    assert main(["simulate", "ffm", "--model", "coulomb", "--set", f"F_0={F0}", "--length", repr(L), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "coulomb"
    assert d["n_slips"] == 0 and d["regime"] == "smooth"
    assert d["max_force_n"] == pytest.approx(F0, rel=1e-4)
    assert d["parameters"]["friction"]["F_0"] == F0


def test_a_contact_model_in_one_file_runs_through_contact(hertz, capsys):
    """Hertz through the registry's general machinery (curve table, Newton on D_bar(A),
    pull-off search): P_bar = D_bar^1.5 on loading (Newton to ~1e-14), nothing out of contact,
    pull-off 0; dimensionally P = 4/3 E* sqrt(R) delta^1.5 whatever the work of adhesion."""
    assert main(["contact", "--model", "hertz", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "hertz"
    assert d["pull_off_normalized"] == 0.0 and d["pull_off_n"] == 0.0
    D = np.array(d["curve"]["penetration_normalized"], dtype=float)
    P = np.array(d["curve"]["load_normalized_loading"], dtype=float)
    assert np.allclose(P[D > 0], D[D > 0] ** 1.5, rtol=1e-9, atol=1e-12)
    assert np.all(P[D < 0] == 0.0)
    par, u = d["parameters"], d["units"]
    delta = 2.0 * u["penetration_m"]
    hertz_law = 4.0 / 3.0 * par["E_star_pa"] * math.sqrt(par["R_m"]) * delta**1.5
    assert 2.0**1.5 * u["load_n"] == pytest.approx(hertz_law, rel=1e-12)


def test_the_example_models_leave_the_registries_as_they_were(coulomb, hertz):
    assert "coulomb" in FRICTION_MODELS and "hertz" in CONTACT_MODELS
    FRICTION_MODELS.unregister("coulomb")
    CONTACT_MODELS.unregister("hertz")
    assert set(FRICTION_MODELS.names()) == BUILTIN_FRICTION and {"bristle", "lugre", "pt"} <= BUILTIN_FRICTION
    assert set(CONTACT_MODELS.names()) == BUILTIN_CONTACT and {"dmt", "jkr", "md"} <= BUILTIN_CONTACT


# ------------------------------------------------------------------ refused at registration
@njit(cache=True)
def _zero_kernel(p, x, v, z):
    return (p[0] * v, 0.0, 0.0, p[0], 0.0, 0.0, 0.0, 0.0)


def _friction(**attrs):
    base = dict(key="viscous-test", title="viscous test law", source="F = b v", n_state=0,
                params=ParamSet([Param("b", 1e-7, "N s/m", "coefficient", positive=True)]), packed=("b",),
                kernel=staticmethod(_zero_kernel), scales=lambda self: (1e-9, 1.0))
    base.update(attrs)
    return type("ViscousTest", (FrictionModel,), {k: v for k, v in base.items() if v is not None})


def _contact(**attrs):
    base = dict(key="flat-test", title="test", source="test", nd_curve=lambda self, A: (A, A, 1.0, 1.0),
                nd_endpoint=lambda self: (0.0, 0.0))
    base.update(attrs)
    return type("FlatTest", (ContactModel,), {k: v for k, v in base.items() if v is not None})


def _probe(**attrs):
    base = dict(key="stub-test", title="test", source="test", params=ParamSet([]),
                build=lambda self, values: None, tip_point=lambda self, values: None)
    base.update(attrs)
    return type("StubTest", (Probe,), {k: v for k, v in base.items() if v is not None})


def _python_kernel(p, x, v, z):  # not compiled: the FFM integrator could not inline it
    return (0.0,) * 8


@pytest.mark.parametrize("registry,make,match", [
    (FRICTION_MODELS, lambda: _friction(kernel=None), "must define 'kernel'"),
    (FRICTION_MODELS, lambda: _friction(kernel=staticmethod(_python_kernel)), "numba-compiled"),
    (FRICTION_MODELS, lambda: _friction(scales=None), "must define 'scales'"),
    (FRICTION_MODELS, lambda: _friction(source=None), "'source'"),
    (FRICTION_MODELS, lambda: _friction(params=None), "'params'"),
    (FRICTION_MODELS, lambda: _friction(packed=("c",)), "packed"),
    (FRICTION_MODELS, lambda: _friction(key="Viscous"), "lower-case string 'key'"),
    (FRICTION_MODELS, lambda: _friction(key="bristle"), "already taken"),
    (FRICTION_MODELS, lambda: _friction(key="tomlinson"), "alias"),
    (CONTACT_MODELS, lambda: _contact(nd_curve=None), "must define 'nd_curve'"),
    (CONTACT_MODELS, lambda: _contact(title=None), "'title'"),
    (PROBES, lambda: _probe(build=None), "must define 'build'"),
    (PROBES, lambda: _probe(params=None), "'params'"),
    (PROBES, lambda: int, "must derive from Probe"),
])
def test_a_model_missing_a_required_piece_is_refused_at_registration(registry, make, match):
    before = registry.names()
    with pytest.raises(RegistryError, match=match):
        registry.register(make())
    assert registry.names() == before


def test_a_complete_model_registers_and_is_found_by_key():
    cls = _friction()
    try:
        FRICTION_MODELS.register(cls)
        m = FRICTION_MODELS.create("viscous-test", b=2e-7)
        assert m.evaluate(0.0, 1e-6, 0.0)["F"] == pytest.approx(2e-13, rel=1e-15)
    finally:
        FRICTION_MODELS.unregister("viscous-test")


# ------------------------------------------------------------------ a diagnose cause in one file
@pytest.fixture
def interference():
    from probedyn.diagnose.causes import CAUSES

    yield _one_file_model("cause_interference", "Fringe670", CAUSES)
    CAUSES.unregister("fringe-670nm")


def test_a_diagnose_cause_in_one_file_is_listed_and_found(interference, capsys, tmp_path):
    """``tests/cause_interference.py`` registers a 670 nm laser's interference fringe. Hidden in a
    Hertz force curve (contact registry, tests/diagnose_truth.py, declared sample modulus, noise
    0.1 nN) with A = 5 nN, the diagnosis lists the new cause, names it first, and the extended
    model explains the curve to the stated noise."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from diagnose_truth import make_force_case

    assert main(["diagnose", "--list-causes", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    rows = listed if isinstance(listed, list) else next(v for v in listed.values() if isinstance(v, list))
    assert "fringe-670nm" in {r.get("key", r.get("cause")) for r in rows}

    path, truth = make_force_case(tmp_path, 7, None, declare_E=True)
    csv = path.with_suffix(".csv")
    z, F, seg = np.loadtxt(csv, delimiter=",", skiprows=1, unpack=True)
    A, phi = 5e-9, 1.0
    F = F + A * np.sin(4 * math.pi * z / 670e-9 + phi)
    np.savetxt(csv, np.column_stack([z, F, seg]), delimiter=",", header="z_m,force_N,segment", comments="",
               fmt=["%.10e", "%.10e", "%d"])
    assert main(["diagnose", str(path), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    f = res["findings"][0]
    assert f["cause"] == "fringe-670nm", [x["cause"] for x in res["findings"]]
    # with the new cause the model explains the data to the stated noise: chi^2 within 3 standard
    # deviations (sqrt(2 dof)) of its degrees of freedom, while the baseline's is far above. (Over a
    # ~0.3 lambda/2 ramp the fringe's amplitude trades against its phase and the tilted baseline, so
    # the amplitude alone is not pinned down; its fitted value is reported with that correlation.)
    dof, chi2 = res["final"]["dof"], res["final"]["chi2"]
    assert abs(chi2 - dof) < 3 * math.sqrt(2 * dof), (chi2, dof)
    assert res["baseline"]["chi2"] > dof + 5 * math.sqrt(2 * dof)
    assert f["parameters"]["A_fringe"]["value"] != 0.0
