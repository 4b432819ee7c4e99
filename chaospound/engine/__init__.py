"""The engine: one integrator composed per (model, contact law, ground motion, method, tangent).

:mod:`.compose` generates and loads the engine of a composition; the template
modules (:mod:`.glue`, :mod:`.events`, :mod:`.loop`) are its text. Physics and
solvers never import each other: only the generated module joins them.
"""
