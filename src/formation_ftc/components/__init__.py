"""Concrete components of the closed loop (the contract is :mod:`formation_ftc.sim.components`).

Every component type has one home, ``components/<kind>/<name>.py``: its equations (pure functions of
arrays, with the paper's equation numbers), its ``@component`` class, its TOML section, its builder and
its registration; shared dynamics live in :mod:`formation_ftc.core`. A component declares what it
provides and needs (:mod:`formation_ftc.sim.contract`), so a law written for one paper runs on any plant
that provides what it needs. Layer: below ``config``/``campaign``/``papers``, above ``sim``.
"""
