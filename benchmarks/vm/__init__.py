"""The reference virtual machine (time-stepping interpolator) for checking ncperf's diagnosis.

``from vm.virtual_machine import simulate, EFFECTS`` with ``benchmarks/`` on sys.path; or run
``python benchmarks/vm/virtual_machine.py --help``.
"""
