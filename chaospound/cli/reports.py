"""The rows every text report starts with (scene or system, model, period ratio,
solver), the last table of a report and the unit row of a state column."""

from __future__ import annotations

from chaospound.cli.output import EXIT_OK, _emit, _table
from chaospound.cli.status import _command_seconds


def _system_header(system) -> list[tuple[str, str]]:
    """The report header of a user's System: name, model, parameters, period, solver."""
    values = ", ".join(f"{k} = {v:g}" for k, v in system.parameter_values.items())
    where = f" ({system.origin})" if system.origin else ""
    return [
        ("system", f"{system.name}{where}"),
        ("model", f"custom ({system.dim} states: {' '.join(system.state_names)})"
                  + ("" if system.has_gap else ", no gap function")),
        ("parameters", values or "-"),
        ("period", f"T = {system.period:.6g}"),
        ("solver", _solver_text(system)),
    ]  # fmt: skip


def _system_document(system) -> dict:
    from chaospound.sweep import system_identity

    return system_identity(system)


def _scene_title(scene) -> str:
    """``name: description``, and for a scene named after a preset whose physics was
    changed (``--set``), what changed: the preset's description may no longer hold."""
    from chaospound.scene import list_presets, load_preset

    title = f"{scene.name}: {scene.description}" if scene.description else scene.name
    if scene.name not in list_presets():
        return title
    changes = scene.physical_changes(load_preset(scene.name))
    if not changes:
        return title
    items = [f"{name} {_value(old)} -> {_value(new)}" for name, (old, new) in changes.items()]
    shown = 4  # the row stays one readable line
    text = ", ".join(items[:shown]) + (f" and {len(items) - shown} more"
                                       if len(items) > shown else "")
    return f"{title}; changed from the preset: {text}"


def _value(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _solver_text(solver) -> str:
    """Method and accuracy setting, as shown in every report header."""
    if solver.method == "rk4":
        return f"rk4, {solver.steps_per_cycle} steps per cycle"
    return f"{solver.method}, rtol {solver.rtol:g}, atol {solver.atol:g}"


def _scene_rows(scene, model: str, period: float) -> list[tuple[str, str]]:
    """The rows every report of a scene starts with: scene, model, period ratio."""
    rows = [("scene", _scene_title(scene)), ("model", model),
            ("period ratio", f"T/T_Ax = {scene.excitation.period_ratio:g} (T = {period:.6g})")]
    ex = scene.excitation
    if ex.ground == "sine" and ex.ground_y_ratio != 0.0:  # the bi-directional sine
        rows.append(("ground y", f"u_gy = {ex.ground_y_ratio:g} sin(t/r + "
                                 f"{ex.ground_y_phase:g})"))
    elif ex.ground != "sine":
        rows.append(("ground motion", _motion_text(ex)))
    rows.append(("contact", _contact_text(scene.contact)))
    return rows


def _motion_text(ex) -> str:
    """A ground motion other than the sine, in one line (a record's file and scale, a
    stochastic motion's process, seed and amplitude)."""
    if ex.ground == "record":
        return f"record {ex.ground_file}, scale {ex.ground_scale:g}"
    if ex.ground == "stochastic":
        amplitude = (f"PGA {ex.ground_pga:g} g" if ex.ground_pga is not None
                     else f"S0 {ex.ground_intensity:g} m^2/s^3")
        return (f"stochastic (Kanai-Tajimi-Clough-Penzien, {ex.ground_envelope} envelope), "
                f"seed {ex.ground_seed}, {amplitude}, scale {ex.ground_scale:g}")
    return ex.ground


def _contact_text(contact) -> str:
    """The contact law: its name, and for a dissipative law its coefficient of restitution."""
    law = contact.contact_law
    text = f"{law}, beta {contact.beta:g}, chi {contact.chi:g}"
    if law != "hertz":
        text += f", restitution {contact.restitution:g}"
    return text + (", no pull" if contact.no_pull else "")


def _emit_report(blocks: list[str], tail: list[tuple[str, str]], plot: str | None) -> int:
    """Print a command's text report: its blocks, then a last table with ``tail``, the
    whole command's wall time and the figure written."""
    tail = [*tail, ("wall time", f"{_command_seconds():.3g} s the whole command")]
    if plot is not None:
        tail.append(("wrote", plot))
    _emit("\n\n".join([*blocks, _table(None, tail, "ll")]) + "\n")
    return EXIT_OK


def _state_unit(name: str) -> str:
    """The unit row of a state column (lengths in A_g, rotations in rad, ...)."""
    rate = name.startswith("d")
    if name.lstrip("d").startswith("th"):
        return "rad omega_Ax" if rate else "rad"
    return "A_g omega_Ax" if rate else "A_g"
