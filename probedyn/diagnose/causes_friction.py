"""Friction causes (filled below)."""
