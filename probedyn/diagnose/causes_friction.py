"""Friction causes: extensions of the quasi-static Prandtl-Tomlinson trace model.

Each ``apply`` edits the state of :class:`probedyn.diagnose.friction.FrictionProblem`:
``n_adh`` (adhesion load / mean load), ``slip_b`` (log-speed slip advance), ``bow`` (scanner
nonlinearity), ``offset``/``drift`` and ``visc`` (in units of the natural force k_x a),
``theta`` (scan angle to the lattice, degrees). Forces in units of k_x a keep the bounds
meaningful for any lever and lattice.
"""

from __future__ import annotations

from probedyn.diagnose.causes import Cause, CauseParam, register


@register
class VelocityLog(Cause):
    id = "velocity-log"
    kind = "friction"
    title = "Thermally activated, logarithmic velocity dependence"
    description = ("Thermal activation lets the tip slip before the athermal instability, the earlier the slower "
                   "the scan: the slip point moves back by a fraction b per e-fold of speed below the fastest scan, "
                   "so friction grows ~ ln(v).")
    needs = "scans at two or more speeds (better: over a decade)"
    source = "thermally activated Prandtl-Tomlinson (Gnecco et al. 2000; Sang et al. 2001); source section 2.1.4"
    params = (CauseParam("slip_b", "1 per e-fold", 0.0, 0.5, (0.05,), "slip advance per e-fold of speed", neutral=0.0),)


@register
class ScannerNonlinearity(Cause):
    id = "scanner-nonlinearity"
    kind = "friction"
    title = "Scanner creep / nonlinear scan position"
    description = ("The real support position bows away from the nominal one: X = X_nom + c (X - X0)(X1 - X)/(X1 - X0) "
                   "(piezo nonlinearity / creep, exact at the calibrated ends); the stick-slip period drifts along the scan.")
    needs = "a trace with several lattice periods"
    source = "quadratic piezo nonlinearity"
    params = (CauseParam("bow", "1", -0.4, 0.4, (0.0,), "bow coefficient c (max error c L / 4 mid-scan)", neutral=0.0),)


@register
class ForceDrift(Cause):
    id = "force-offset-drift"
    kind = "friction"
    title = "Lateral-force offset and drift"
    description = ("A constant offset and a linear drift in time of the lateral-force signal (photodiode / "
                   "torsion zero), in units of k_x a: forward and backward traces no longer symmetric about zero.")
    needs = "forward and backward traces"
    source = "F_meas = F + o + d (t - t_mid) / T"
    params = (
        CauseParam("offset", "k_x a", -5.0, 5.0, (0.0,), "offset / (k_x a)", neutral=0.0),
        CauseParam("drift", "k_x a per scan", -5.0, 5.0, (0.0,), "drift over one scan / (k_x a)", neutral=0.0),
    )


@register
class LatticeMisalignment(Cause):
    id = "lattice-misalignment"
    kind = "friction"
    title = "2D zigzag from lattice misalignment"
    description = ("The scan runs at an angle theta to the lattice rows: in the separable square-lattice potential "
                   "-U0 [cos(2 pi x/a) + cos(2 pi y/a)] with isotropic lateral stiffness, the tip sticks and slips "
                   "in x and y alternately (zigzag); the lateral force along the scan is cos(theta) F_x + sin(theta) F_y "
                   "with periods a/cos(theta) and a/sin(theta).")
    needs = "a trace with several lattice periods"
    source = "2D stick-slip, source section 2.1.4.1 (Fig 2.7, angle gamma) and 4.1.1 (zigzag pushing)"
    params = (CauseParam("theta", "deg", 0.0, 45.0, (8.0, 20.0, 35.0), "scan angle to the lattice axis", neutral=0.0),)


@register
class ViscousFriction(Cause):
    id = "viscous-friction"
    kind = "friction"
    title = "Viscous term"
    description = ("A friction force proportional to sliding speed, c_v v (source eqs 2.7/2.10: F_nu V), "
                   "given as the force at the fastest scan in units of k_x a: friction grows linearly with v.")
    needs = "scans at two or more speeds"
    source = "eqs 2.7 and 2.10 (viscous coefficient F_nu, N s/m; SOURCE-NOTES item 9)"
    params = (CauseParam("visc", "k_x a at v_max", 0.0, 10.0, (0.05,), "viscous force at the fastest scan / (k_x a)", neutral=0.0),)


@register
class AdhesionLoad(Cause):
    id = "adhesion-load"
    kind = "friction"
    title = "Load dependence through adhesion (or a capillary meniscus)"
    description = ("Friction proportional to the total load N + N_adh instead of N (Derjaguin's law; a meniscus "
                   "adds a load-independent capillary force the same way): friction is finite at zero load.")
    needs = "scans at two or more normal loads"
    source = "section 2.2.4 (adhesion-friction coupling)"
    params = (CauseParam("n_adh", "mean load", -0.9, 20.0, (0.3,), "adhesion load / mean normal load", neutral=0.0),)

