"""Vibrational nano-placing (section 4.2 of the source): one module per phase.

==================  ===============================================================  ==============
module              what                                                             source
==================  ===============================================================  ==============
:mod:`.probe`       the probe's normal-direction numbers (FEM, beam, Table 4.4),     Table 4.4,
                    Table 4.4's mass against the geometry                            SOURCE-NOTES 10
:mod:`.approach`    first mode + van der Waals force: equilibria, jump into          (4.13)-(4.21),
                    contact, forced response, frequency shift (small amplitude,      Fig 4.20
                    Giessibl, exact orbit, time simulation)
:mod:`.capture`     cantilever + sample on a contact spring: frequency equation      (4.22)-(4.41),
                    (corrected sign), mode shapes, FEM check, MD linearisation       Figs 4.18, 4.21,
                                                                                     SOURCE-NOTES 4
:mod:`.release`     sample on the full Maugis-Dugdale contact under tip              (4.42),
                    oscillation: released / recaptured / attached, outcome maps      Figs 4.22-4.23
                    on Dask (compiled integrator in :mod:`._kernel`)
:mod:`.landing`     flight under probe and substrate attraction and gravity,        (4.43)-(4.44),
                    tilt from the tip amplitude, landing radius                      Figs 4.27-4.28,
                                                                                     SOURCE-NOTES 6
:mod:`.multi`       several samples: Rayleigh-Ritz (polynomial, FEM modes),          (4.45)-(4.55),
                    exact reference, inverse problem and identifiability,           Figs 4.24-4.26,
                    selective release                                                SOURCE-NOTES 7, 11
:mod:`.studies`     the parameter studies behind the figures and the docs            section 4.2.4
==================  ===============================================================  ==============

Units SI throughout. Every model states its assumptions in its module docstring; departures
from the printed equations are listed at the end of docs/source-departures.md and explained
in docs/placing.md.
"""

from .probe import MASS_SOURCES, TABLE, PlacingProbe, mass_plausibility, table_beam_geometry

__all__ = ["PlacingProbe", "TABLE", "MASS_SOURCES", "mass_plausibility", "table_beam_geometry"]
