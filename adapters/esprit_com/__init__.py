"""A1 + A3 adapter for ESPRIT through pythonnet (issue 3; not registered yet)."""
