"""A1 adapter for APT CL data / CLSF (issue 3; not registered yet)."""
