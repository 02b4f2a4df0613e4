"""Adapters: A1 extract (tool paths from files and hosts) and A3 display (annotations back)."""
