"""Everything ``probedyn contact`` reports for one contact model of the registry: the
normalised load–penetration curve on its loading / unloading / unstable branches (Fig 2.19),
the pull-off and jump-out loads, the contact transition, and for Maugis–Dugdale the published
COS fit of the pull-off beside it."""

from __future__ import annotations

from typing import Any

import numpy as np

from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.contact.carpick import REFERENCE, cos_fit_pull_off


def contact_summary(model: str = "md", lam: float | None = None, params: dict[str, Any] | None = None,
                    n_points: int = 201, D_range: tuple[float, float] = (-2.0, 3.0)) -> dict[str, Any]:
    """The contact model ``model`` with parameter overrides ``params`` (SI; ``lam`` sets the
    work of adhesion through 2.24) as a JSON-able dict: pull-off (normalised and in N), jump-out,
    contact transition, parameters, scales and the curves sampled at ``n_points`` penetrations."""
    kw: dict[str, Any] = dict(params or {})
    if lam is not None:
        kw["lam"] = lam
    m = get_contact_model(model, **kw)
    if not m.adhesive:
        return _indenter_summary(m, n_points)
    po = m.nd_pull_off()
    D = np.linspace(D_range[0], D_range[1], n_points)
    loading = m.nd_state(D, "loading")
    unloading = m.nd_state(D, "unloading")
    unstable = m.nd_state(D, "unstable")
    curves = m.nd_curves(D_range)
    s = m.scales
    res: dict[str, Any] = dict(
        model=m.name, title=m.title, equations=m.equations, adhesive=True, lam=m.lam,
        pull_off_normalized=po["P_pull_off"],
        pull_off_n=m.pull_off_force(),
        contact_radius_at_pull_off_normalized=po["A_pull_off"],
        jump_out_load_normalized=po["P_jump_out"],
        jump_out_penetration_normalized=po["D_jump_out"],
        contact_transition=dict(penetration_normalized=curves["D0"], load_normalized=curves["P0"]),
        parameters=m.describe(),
        units=dict(load_n=s.P_unit, penetration_m=s.d_unit, contact_radius_m=s.a_unit),
        curve=dict(
            penetration_normalized=D,
            load_normalized_loading=loading["P"],
            load_normalized_unloading=unloading["P"],
            load_normalized_unstable=unstable["P"],
            contact_radius_normalized_unloading=unloading["A"],
        ),
        parametric_curve=dict(contact_radius_normalized=curves["A"][::3],
                              penetration_normalized=curves["D"][::3], load_normalized=curves["P"][::3]),
    )
    if m.name == "md":
        fit = cos_fit_pull_off(m.lam)
        res["pull_off_published_fit"] = dict(reference=REFERENCE, value=fit,
                                             relative_difference=po["P_pull_off"] / fit - 1.0)
    return res


def _indenter_summary(m, n_points: int) -> dict[str, Any]:
    """A non-adhesive law (``adhesive = False``: a cone or pyramid blunted by the tip radius): no
    attraction, so no work of adhesion, lambda, pull-off, jump-out or contact transition (the
    contact starts at zero load at zero penetration and the load grows monotonically: loading and
    unloading coincide and a spring of any stiffness follows it without a jump). Reported: the
    law's geometry (equivalent cone, cap edge), its units (loads in E* R^2, lengths in R) and the
    load against penetration out to three cap-edge depths, where the flanks carry the load."""
    s = m.scales
    desc = m.describe()
    D_edge = desc.get("cap_edge_depth_m", s.d_unit) / s.d_unit
    D = np.linspace(0.0, 3.0 * D_edge, n_points)
    st = m.nd_state(D, "loading")
    return dict(model=m.name, title=m.title, equations=m.equations, adhesive=False, parameters=desc,
                cap_edge_load_n=float(m.force(D_edge * s.d_unit)),
                units=dict(load_n=s.P_unit, penetration_m=s.d_unit, contact_radius_m=s.a_unit),
                curve=dict(penetration_normalized=D, load_normalized_loading=st["P"],
                           contact_radius_normalized_loading=st["A"]))
