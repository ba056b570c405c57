"""Path tracking and probe control of the smart probes (source sections 3.2.3, 3.3.3, 3.4, 3.5).

Modules: :mod:`.paths` (desired tip paths), :mod:`.actuation` (gains per volt, eccentric tube),
:mod:`.plants` (plant interface, two-body model 3.37), :mod:`.disturbance` (KBr substrate 3.45),
:mod:`.inversion` (quasi-static and dynamic inverses), :mod:`.controllers` (open loop, slow 3.54,
composite 3.50-3.54, PID), :mod:`.simulate` (closed-loop simulation), :mod:`.studies`.
The smart probes' plants (a probe name -> its two-body model) are built one layer up, in
:mod:`probedyn.probes.tracking`; docs/tracking.md has the results.
"""
