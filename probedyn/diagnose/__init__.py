"""``probedyn diagnose``: what probedyn's own simulation gets wrong on a measurement, why, and
what extending the model gains (see docs/diagnose.md)."""
