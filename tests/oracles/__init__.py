"""Independent oracles for the ``rcsa`` library (no code shared with it).

``timoshenko_fe``: a Timoshenko beam finite-element model (element, assembler, solvers);
``fe_assembly``: builds that model from a contract assembly dict (``docs/contract.md``), with the
physical "effects" used as truth for the withheld-effect diagnosis benchmark.
"""
