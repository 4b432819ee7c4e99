"""The model's units, as every output states them (docs/model.md section 2).

Everything is dimensionless: lengths in A_g (the ground displacement
amplitude), time t = tau omega_Ax, velocities in A_g omega_Ax, forces in
A_g k_Ax. The sweep files' ``units`` attribute and the ``units`` object of the
command line's JSON documents are this dictionary.
"""

UNITS = {
    "time": "normalised, t = tau omega_Ax",
    "length": "A_g (ground displacement amplitude)",
    "velocity": "A_g omega_Ax",
    "force": "A_g k_Ax",
    "exponents": "per unit normalised time (multiply by the period T for per cycle)",
    "phase": "fraction of the excitation period, in [0, 1)",
}
