"""Functions and constants shared by test modules of more than one file (fixtures live in conftest.py).

Test modules import from here, never from one another: ``from _helpers.coupling import MAPPINGS``.
``tests/`` is on ``sys.path`` because ``tests/conftest.py`` is imported from it (pytest's default
``prepend`` import mode); the scripts in ``tests/validation`` put it there themselves.

Modules
-------
coupling      random particles and gas states over a grid, the voidage mappings tested
gas_fields    the tiny coupled jet bed that writes gas fields
hardsphere    the built-in pour case with hard spheres, its energy error and overlap
neighbours    random polydisperse packings
plotting      the plotting commands driven in-process, PNG decoding and comparison
settling      a lone sphere settling in still gas (case and constants)
umf_sweep     the u_mf sweep bed (case and constants)
"""
