"""Concrete components of the closed loop (the contract is :mod:`formation_ftc.sim.components`).

Each module holds the components of one kind; each component is a thin, typed wrapper around the pure
equations in :mod:`formation_ftc.core` and :mod:`formation_ftc.blocks` (the equation numbers sit
there), so a law written for one paper runs on any plant that provides what it needs. Layer: below
``config``/``campaign``/``papers``, above ``sim``.
"""
