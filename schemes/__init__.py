"""Simulations driven by reduced probe models: friction, contact, pushing, placing; parameter sweeps."""
