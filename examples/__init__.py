"""Example programs (paper experiments and a Z-level mould cavity) and their generator."""
