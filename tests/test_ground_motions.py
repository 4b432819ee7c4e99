"""The ground-motion modules of chaospound.physics.ground (issue 15).

- sine and none: the library sine (bitwise), and rest;
- record: the piecewise-cubic displacement against exact rational integrals of a
  piecewise-linear acceleration, second-order convergence on a sampled sine,
  continuity at samples, the baseline correction, next_kink, the AT2 and text
  readers on every header variant, one-line errors on bad files;
- stochastic: same seed, same bits; the averaged periodogram of many stationary
  realisations against the Kanai-Tajimi-Clough-Penzien density (closed form,
  aliased at the sample rate) within its statistical error.

Every file is written here to tmp_path.
"""

from __future__ import annotations

import math
import struct
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from chaospound.physics.ground import none, record, records_io, sine, stochastic

MODULES = (sine, none, record, stochastic)


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


def same_bits(a: tuple, b: tuple) -> bool:
    return len(a) == len(b) and all(bits(x) == bits(y) for x, y in zip(a, b, strict=True))


# --------------------------------------------------------------- interface
@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.NAME)
def test_interface(module):
    for name in ("at", "at_y", "acceleration", "anchor", "shifted", "at_anchor", "next_kink",
                 "block", "period"):
        assert callable(getattr(module, name)), name
    assert isinstance(module.NAME, str) and isinstance(module.PARAMETERS, tuple)
    assert isinstance(module.PERIODIC, bool) and isinstance(module.KINKS, bool)


# --------------------------------------------------------------- sine, none
times = st.floats(-1e4, 1e4, allow_nan=False)
shifts = st.one_of(st.floats(-0.5, 0.5), st.floats(-20.0, 20.0))
ratios = st.floats(0.2, 5.0)


@settings(max_examples=300, deadline=None)
@given(t=times, shift=shifts, r=ratios, base=st.integers(0, 4))
def test_sine_is_the_library_sine(t, shift, r, base):
    """``at`` and ``anchor`` are the library's sine and cosine bit for bit; the carried
    phase moved by angle addition equals the direct evaluation to a few ulps. (That
    the engine's results are bitwise those of the id-dispatching kernels it replaced
    is benchmarks/golden.py's check, run at the redesign.)"""
    new = np.full(base + 3, np.nan)
    new[base:] = sine.block({"period_ratio": r})
    assert same_bits(sine.at(t, new, base), (math.sin(t / r), math.cos(t / r) / r))
    anchor = sine.anchor(t, new, base)
    assert same_bits(anchor, (math.sin(t / r), math.cos(t / r)))
    moved = sine.shifted(anchor[0], anchor[1], shift, new, base)
    direct = (math.sin(t / r + shift / r), math.cos(t / r + shift / r))
    assert np.allclose(moved, direct, rtol=0.0, atol=1e-14 * (1.0 + abs(t / r)))
    assert same_bits(sine.at_anchor(moved[0], moved[1], new, base), (moved[0], moved[1] / r))
    assert sine.at_y(t, new, base) == (0.0, 0.0)
    assert math.isinf(sine.next_kink(t, new, base))


@settings(max_examples=100, deadline=None)
@given(t=times, shift=shifts)
def test_none_is_at_rest(t, shift):
    p = np.concatenate([[np.nan], none.block({})])
    assert same_bits(none.at(t, p, 1), (0.0, 0.0))
    assert same_bits(none.anchor(t, p, 1), (0.0, 1.0))
    assert same_bits(none.shifted(0.0, 1.0, shift, p, 1), (0.0, 1.0))
    assert same_bits(none.at_anchor(0.0, 1.0, p, 1), (0.0, 0.0))
    assert none.acceleration(t, p, 1) == 0.0 and none.at_y(t, p, 1) == (0.0, 0.0)


@settings(max_examples=100, deadline=None)
@given(t=st.floats(-100.0, 100.0), r=ratios, y_ratio=st.floats(0.1, 2.0),
       y_phase=st.floats(-math.pi, math.pi))
def test_sine_y_component_and_acceleration(t, r, y_ratio, y_phase):
    p = sine.block({"period_ratio": r, "y_ratio": y_ratio, "y_phase": y_phase})
    u, v = sine.at_y(t, p, 0)
    assert u == pytest.approx(y_ratio * math.sin(t / r + y_phase), abs=1e-14)
    assert v == pytest.approx(y_ratio * math.cos(t / r + y_phase) / r, abs=1e-13)
    assert sine.acceleration(t, p, 0) == pytest.approx(-math.sin(t / r) / r**2, abs=1e-13)
    assert sine.period(p) == 2.0 * math.pi * r


def test_sine_block_refuses_bad_ratio():
    with pytest.raises(ValueError, match="period_ratio"):
        sine.block({"period_ratio": -1.0})


# --------------------------------------------------------------- record: exactness
def exact_motion(times, accel, t):
    """(u, v) at t of the piecewise-linear acceleration, in exact rationals.

    Cauchy's formula u(t) = int (t - s) a(s) ds, v(t) = int a(s) ds over the
    samples' span up to t (a = 0 outside), from u = v = 0 before the first sample.
    """
    T = [Fraction(x) for x in times]
    A = [Fraction(x) for x in accel]
    t = Fraction(t)
    u = v = Fraction(0)
    for k in range(len(T) - 1):
        lo, hi = T[k], min(T[k + 1], t)
        if hi <= lo:
            break
        beta = (A[k + 1] - A[k]) / (T[k + 1] - T[k])
        alpha = A[k] - beta * T[k]

        def prim_u(s, alpha=alpha, beta=beta):
            return t * alpha * s + (t * beta - alpha) * s**2 / 2 - beta * s**3 / 3

        def prim_v(s, alpha=alpha, beta=beta):
            return alpha * s + beta * s**2 / 2

        u += prim_u(hi) - prim_u(lo)
        v += prim_v(hi) - prim_v(lo)
    return float(u), float(v)


def random_record(seed: int, n: int, uniform: bool):
    rng = np.random.default_rng(seed)
    if uniform:
        times = 0.3 + np.arange(n) * 0.05
    else:
        times = 0.3 + np.cumsum(rng.uniform(0.01, 0.2, n)) - 0.01
    accel = rng.normal(0.0, 1.0, n)
    return times, accel


@pytest.mark.parametrize("uniform", [True, False], ids=["uniform", "non-uniform"])
def test_record_matches_exact_integrals(uniform):
    times, accel = random_record(1, 60, uniform)
    p = record.block_from_samples(times, accel, baseline="none")
    rng = np.random.default_rng(2)
    probes = np.concatenate([rng.uniform(times[0] - 0.5, times[-1] + 0.5, 150), times,
                             [times[0] - 1.0, times[-1] + 2.0]])
    scale = max(abs(x) for x in exact_motion(times, accel, times[-1])) + 1.0
    for t in probes:
        u, v = record.at(float(t), p, 0)
        u_ref, v_ref = exact_motion(times, accel, float(t))
        assert abs(u - u_ref) <= 1e-12 * scale, (t, u, u_ref)
        assert abs(v - v_ref) <= 1e-12 * scale, (t, v, v_ref)
        inside = times[0] <= t < times[-1]
        a_ref = np.interp(t, times, accel) if inside else 0.0
        assert record.acceleration(float(t), p, 0) == pytest.approx(a_ref, abs=1e-12)


def test_record_sampled_sine_converges_at_second_order():
    """a = -sin t sampled at dt: u -> sin t - t (from rest) at order 2 (linear interpolation)."""
    span = 4.0 * math.pi
    probe = np.linspace(0.0, span, 2001)
    errors = []
    steps = [0.2, 0.1, 0.05, 0.025]
    for dt in steps:
        t = np.arange(int(round(span / dt)) + 1) * dt
        p = record.block_from_samples(t, -np.sin(t), baseline="none")
        err = max(abs(record.at(float(s), p, 0)[0] - (math.sin(s) - s)) for s in probe)
        errors.append(err)
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:], strict=False)]
    assert errors[-1] < 1e-3
    assert all(1.9 < q < 2.1 for q in orders), (errors, orders)


def test_record_of_a_sampled_sine_reproduces_the_sine_module():
    """Sine sampled at dt, from (u, u') = (0, 1/r): u and u' converge to sine.at at order 2."""
    r = 0.8
    p_sine = sine.block({"period_ratio": r})
    span = 3.0 * 2.0 * math.pi * r
    probe = np.linspace(0.0, span, 1501)
    errors = []
    for dt in (0.16, 0.08, 0.04, 0.02):
        t = np.arange(int(round(span / dt)) + 1) * dt
        a = np.array([sine.acceleration(float(x), p_sine, 0) for x in t])
        p = record.block_from_samples(t, a, baseline="none", initial_x=(0.0, 1.0 / r))
        err = 0.0
        for x in probe:
            u, v = record.at(float(x), p, 0)
            u_ref, v_ref = sine.at(float(x), p_sine, 0)
            err = max(err, abs(u - u_ref), abs(v - v_ref))
        errors.append(err)
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:], strict=False)]
    assert all(1.9 < q < 2.1 for q in orders), (errors, orders)
    u, v = record.at(-0.5, p, 0)  # before the first sample: the initial state's straight line
    assert (u, v) == (-0.5 / r, 1.0 / r)


def test_record_continuity_at_samples():
    times, accel = random_record(3, 40, uniform=False)
    p = record.block_from_samples(times, accel)
    for t in times[1:-1]:
        before = float(np.nextafter(t, -np.inf))
        u0, v0 = record.at(before, p, 0)
        u1, v1 = record.at(float(t), p, 0)
        assert abs(u1 - u0) < 1e-12 and abs(v1 - v0) < 1e-12
        a0 = record.acceleration(before, p, 0)
        assert abs(record.acceleration(float(t), p, 0) - a0) < 1e-9


def test_record_baseline_rest():
    times, accel = random_record(4, 200, uniform=True)
    accel += 0.05  # a baseline offset: without correction u grows like t^2
    raw = record.block_from_samples(times, accel, baseline="none")
    p = record.block_from_samples(times, accel, baseline="rest")
    assert abs(record.at(float(times[-1]), raw, 0)[0]) > 0.1
    n = len(times)
    corrected = p[3 + 3 * n : 3 + 4 * n]
    correction = accel - corrected
    line = np.polyval(np.polyfit(times, correction, 1), times)
    assert np.max(np.abs(correction - line)) < 1e-13  # linear in t: stays piecewise linear
    for t in (times[-1], times[-1] + 10.0):
        u, v = record.at(float(t), p, 0)
        assert abs(u) < 1e-12 and abs(v) < 1e-12
    assert record.at(float(times[0]) - 1.0, p, 0) == (0.0, 0.0)


@pytest.mark.parametrize("uniform", [True, False], ids=["uniform", "non-uniform"])
def test_record_next_kink(uniform):
    times, accel = random_record(5, 50, uniform)
    p = np.concatenate([[np.nan, np.nan], record.block_from_samples(times, accel)])
    rng = np.random.default_rng(6)
    for t in np.concatenate([rng.uniform(times[0], times[-1], 300), times[:-1]]):
        expected = times[np.searchsorted(times, t, side="right")]
        assert record.next_kink(float(t), p, 2) == expected
    assert record.next_kink(float(times[0]) - 3.0, p, 2) == times[0]
    assert math.isinf(record.next_kink(float(times[-1]), p, 2))
    assert math.isinf(record.next_kink(float(times[-1]) + 1.0, p, 2))
    assert record.KINKS and not record.PERIODIC


def test_record_carried_state_and_y():
    times, accel = random_record(7, 30, uniform=True)
    other = np.cos(times)
    p = record.block_from_samples(times, accel, other, baseline="none")
    single = record.block_from_samples(times, other, baseline="none")
    c0, c1 = record.anchor(0.7, p, 0)
    c0, c1 = record.shifted(c0, c1, 0.25, p, 0)
    assert record.at_anchor(c0, c1, p, 0) == record.at(0.7 + 0.25, p, 0)
    assert record.at_y(0.95, p, 0) == record.at(0.95, single, 0)
    assert record.at_y(0.95, single, 0) == (0.0, 0.0)


# --------------------------------------------------------------- record files
AT2_VALUES = ["0.1260E-02", ".1300E-02", "-.4313E-03", "-0.1234567E-01", "2.5E-03",
              "0.0", "-1.0E-04"]


def at2_text(header: str, per_line: int = 5, units: str = "G") -> str:
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD",
             "IMPERIAL VALLEY 10/15/79 2316, EL CENTRO ARRAY #6, 230",
             f"ACCELERATION TIME HISTORY IN UNITS OF {units}", header]
    values = [f"{v:>15}" for v in AT2_VALUES]
    lines += ["".join(values[i : i + per_line]) for i in range(0, len(values), per_line)]
    return "\n".join(lines) + "\n"


HEADERS = {
    "classic": ("NPTS= 7, DT= .0100 SEC", 0.01),
    "padded-comma": ("NPTS=  7, DT=   .0050 SEC,", 0.005),
    "lowercase-spaces": ("npts = 7 , dt = 0.005 sec", 0.005),
    "fortran-dt": ("NPTS=      7, DT= 0.5000E-02 SEC", 0.005),
    "old-peer": ("     7   .0200   NPTS, DT", 0.02),
}


@pytest.mark.parametrize("name", HEADERS)
@pytest.mark.parametrize("per_line", [5, 3, 1])
def test_at2_header_variants(tmp_path, name, per_line):
    header, dt = HEADERS[name]
    path = tmp_path / "rec.AT2"
    path.write_text(at2_text(header, per_line))
    step, values, units = records_io.read_at2(path)
    assert step == dt and units == "g"
    assert values.tolist() == [float(v) for v in AT2_VALUES]


def test_at2_glued_fields_d_exponent_and_units(tmp_path):
    path = tmp_path / "glued.at2"
    body = at2_text("NPTS= 7, DT= .0100 SEC", units="CM/S/S").splitlines()[:4]
    body += ["  .1260E-02  .1300E-02-.4313E-03-0.1234567D-01", "2.5E-03 0.0", "-1.0E-04"]
    path.write_text("\n".join(body) + "\n")
    step, values, units = records_io.read_at2(path)
    assert units == "cm/s^2" and step == 0.01
    assert values.tolist() == [float(v) for v in AT2_VALUES]
    rec = records_io.load_record(path, scale=2.0)
    assert np.array_equal(rec.x, values * 0.01 * 2.0) and rec.y is None
    assert np.array_equal(rec.time, np.arange(7) * 0.01)


def test_at2_without_units_and_bom(tmp_path):
    path = tmp_path / "plain.AT2"
    text = at2_text("NPTS= 7, DT= .0100 SEC").replace("IN UNITS OF G", "")
    path.write_text("\ufeff" + text, encoding="utf-8")
    assert records_io.read_at2(path)[2] is None
    g = records_io.STANDARD_GRAVITY
    assert records_io.load_record(path).x[0] == float(AT2_VALUES[0]) * g
    assert records_io.load_record(path, units="cm/s^2").x[0] == float(AT2_VALUES[0]) * 0.01
    text_file = tmp_path / "bom.txt"
    text_file.write_text("\ufeff0 1\n0.01 2\n", encoding="utf-8")
    assert records_io.load_record(text_file, units="m/s^2").x.tolist() == [1.0, 2.0]
    with pytest.raises(ValueError, match="'omega' is required"):
        record.block({"file": str(path), "length_scale": 0.05})


def test_two_at2_components_and_model_units(tmp_path):
    x, y = tmp_path / "x.AT2", tmp_path / "y.AT2"
    x.write_text(at2_text("NPTS= 7, DT= .0100 SEC"))
    y.write_text(at2_text("NPTS=  7, DT=   .0100 SEC,"))
    rec = records_io.load_record([x, y])
    g = records_io.STANDARD_GRAVITY
    assert np.array_equal(rec.x, np.array([float(v) for v in AT2_VALUES]) * g)
    assert np.array_equal(rec.y, rec.x)
    length, omega = 0.05, 2.0 * math.pi * 1.5
    t, a_x, a_y = records_io.to_model(rec, length, omega)
    assert np.allclose(t, rec.time * omega, rtol=1e-15)
    assert np.allclose(a_x, rec.x / (length * omega**2), rtol=1e-15)
    p = record.block({"file": [str(x), str(y)], "length_scale": length, "omega": omega})
    assert np.array_equal(p, record.block_from_samples(t, a_x, a_y))
    assert p[1] == 2.0


def test_text_formats(tmp_path):
    t = np.array([0.0, 0.01, 0.025, 0.04])
    a = np.array([0.0, 1.5, -2.0, 0.5])
    two = tmp_path / "two.txt"
    rows = "".join(f"{x}, {y}\n" for x, y in zip(t, a, strict=True))
    two.write_text("# a comment\ntime acc\n" + rows)
    rec = records_io.load_record(two, units="cm/s^2")
    assert np.array_equal(rec.time, t) and np.array_equal(rec.x, a * 0.01)
    three = tmp_path / "three.dat"
    three.write_text("".join(f"{x}\t{y} {-y}\n" for x, y in zip(t, a, strict=True)))
    rec = records_io.load_record(three, units="m/s^2")
    assert np.array_equal(rec.y, -a)
    one = tmp_path / "one.txt"
    one.write_text("\n".join(str(v) for v in a) + "\n")
    rec = records_io.load_record(one, units="gal", dt=0.02)
    assert np.array_equal(rec.time, np.arange(4) * 0.02)
    rec_g = records_io.load_record(one, dt=0.02, scale=0.5)
    assert np.array_equal(rec_g.x, a * records_io.STANDARD_GRAVITY * 0.5)


BAD_FILES = {  # name: (file name, content, load_record kwargs, words of the message)
    "npts-too-large": ("a.AT2", at2_text("NPTS= 9, DT= .0100 SEC"), {}, "NPTS=9"),
    "npts-too-small": ("a2.AT2", at2_text("NPTS= 5, DT= .0100 SEC"), {}, "but 7 values"),
    "non-numeric": ("b.AT2", at2_text("NPTS= 7, DT= .01 SEC").replace("2.5E-03", "2.5X03"),
                    {}, "non-numeric"),
    "empty": ("c.AT2", "", {}, "empty"),
    "blank": ("c2.txt", "\n  \n", {}, "empty"),
    "no-header": ("d.AT2", "PEER\n.1 .2 .3\n", {}, "NPTS"),
    "at2-unknown-units": ("e.AT2", at2_text("NPTS= 7, DT= .01 SEC", units="FURLONGS"), {},
                          "unknown units"),
    "text-unknown-units": ("f.txt", "0 1\n1 2\n", {"units": "ft/s^2"}, "unknown units"),
    "conflicting-units": ("g.AT2", at2_text("NPTS= 7, DT= .01 SEC"), {"units": "cm/s^2"},
                          "states units"),
    "non-increasing": ("h.txt", "0 1\n0.02 2\n0.01 3\n", {}, "strictly increasing"),
    "repeated-time": ("i.txt", "0 1\n0.01 2\n0.01 3\n", {}, "strictly increasing"),
    "text-non-numeric": ("j.txt", "0 1\n0.01 abc\n", {}, "non-numeric"),
    "ragged": ("k.txt", "0 1\n0.01 2 3\n", {}, "columns"),
    "one-column-no-dt": ("l.txt", "1\n2\n3\n", {}, "needs the sample interval"),
    "zero-dt": ("m.AT2", at2_text("NPTS= 7, DT= 0.0 SEC"), {}, "DT="),
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_files_one_line_value_error(tmp_path, case):
    name, content, kwargs, words = BAD_FILES[case]
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(ValueError) as info:
        records_io.load_record(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message and str(path) in message and words in message, message
    with pytest.raises(ValueError):  # the block builder passes it on unchanged
        record.block({"file": str(path), "length_scale": 0.05, "omega": 9.0, **kwargs})


def test_two_files_on_different_time_bases(tmp_path):
    x, y = tmp_path / "x.AT2", tmp_path / "y.AT2"
    x.write_text(at2_text("NPTS= 7, DT= .0100 SEC"))
    y.write_text(at2_text("NPTS= 7, DT= .0200 SEC"))
    with pytest.raises(ValueError, match="time base"):
        records_io.load_record([x, y])


# --------------------------------------------------------------- stochastic
SPEC = {"omega_g": 2.5, "zeta_g": 0.6, "omega_f": 0.25, "zeta_f": 0.6, "intensity": 1.0,
        "dt": 0.1, "duration": 409.5, "seed": 1}


def test_stochastic_same_seed_same_bits():
    spec = {**SPEC, "duration": 60.0, "envelope": "jennings", "t_rise": 5.0,
            "t_plateau": 20.0, "decay": 0.1, "components": 2, "seed": 12345}
    first = stochastic.block(spec)
    assert first.tobytes() == stochastic.block(dict(spec)).tobytes()
    assert first.tobytes() != stochastic.block({**spec, "seed": 12346}).tobytes()
    t, a_x, a_y = stochastic.generate(spec)
    assert not np.array_equal(a_x, a_y)
    assert abs(np.corrcoef(a_x, a_y)[0, 1]) < 0.2
    assert stochastic.at(3.0, first, 0) == record.at(3.0, first, 0)


def test_envelopes():
    t = np.array([0.0, 2.5, 5.0, 10.0, 20.0, 30.0])
    jennings = stochastic.envelope(t, {**SPEC, "envelope": "jennings", "t_rise": 5.0,
                                       "t_plateau": 20.0, "decay": 0.1})
    assert np.allclose(jennings, [0.0, 0.25, 1.0, 1.0, 1.0, math.exp(-1.0)], rtol=1e-15)
    sh = stochastic.envelope(np.linspace(0.0, 40.0, 4001),
                             {**SPEC, "envelope": "saragoni-hart", "b": 2.0, "c": 0.25})
    assert sh.max() == pytest.approx(1.0, abs=1e-12) and np.argmax(sh) == 800  # t_peak = b/c
    with pytest.raises(ValueError, match="envelope"):
        stochastic.envelope(t, {**SPEC, "envelope": "boxcar"})


def kt_cp_reference(omega, wg, zg, wf, zf, s0):
    """The KT-CP density, written out independently of the module."""
    kt = (wg**4 + 4 * zg**2 * wg**2 * omega**2) / ((wg**2 - omega**2) ** 2
                                                    + 4 * zg**2 * wg**2 * omega**2)
    cp = omega**4 / ((wf**2 - omega**2) ** 2 + 4 * zf**2 * wf**2 * omega**2)
    return s0 * kt * cp


def periodogram_statistic(density_kwargs, averaged, omega, dt, realisations):
    """(mean z^2, max |z|) of z = sqrt(R) (I / S_aliased - 1) on every other bin in the band."""
    aliases = np.arange(-300, 301) * (2.0 * math.pi / dt)
    density = kt_cp_reference(omega[:, None] + aliases[None, :], **density_kwargs).sum(axis=1)
    band = np.nonzero((omega > 0.5) & (omega < 15.0))[0][::2]  # Hann: every other bin ~independent
    z = math.sqrt(realisations) * (averaged[band] / density[band] - 1.0)
    return float(np.mean(z**2)), float(np.max(np.abs(z))), len(band)


def test_stochastic_periodogram_matches_kt_cp_density():
    """Averaged Hann periodogram of 400 stationary realisations against S aliased at 1/dt.

    Each bin's average is S Gamma(R, 1/R): z = sqrt(R) (I/S - 1) has mean 0 and
    variance 1, and bins two apart are nearly independent with a Hann window
    (periodogram correlation 1/36). The bound on mean z^2 is 5 standard deviations
    of a chi-square mean; a density 5 % too strong or a zeta_g 10 % off fails it.
    """
    realisations = 400
    runs = np.array([stochastic.generate({**SPEC, "seed": 1000 + i})[1]
                     for i in range(realisations)])
    n, dt = runs.shape[1], SPEC["dt"]
    window = 0.5 - 0.5 * np.cos(2.0 * math.pi * np.arange(n) / n)
    spectra = np.abs(np.fft.rfft(runs * window, axis=1)) ** 2
    averaged = dt / (2.0 * math.pi * np.sum(window**2)) * spectra.mean(axis=0)
    omega = 2.0 * math.pi * np.fft.rfftfreq(n, dt)
    model = {"wg": 2.5, "zg": 0.6, "wf": 0.25, "zf": 0.6, "s0": 1.0}
    mean_z2, max_z, bins = periodogram_statistic(model, averaged, omega, dt, realisations)
    bound = 1.0 + 5.0 * math.sqrt(2.0 / bins)
    assert bins > 400
    assert mean_z2 < bound and max_z < 5.0, (mean_z2, max_z)
    for wrong in ({**model, "s0": 1.05}, {**model, "zg": 0.66}):
        assert periodogram_statistic(wrong, averaged, omega, dt, realisations)[0] > bound


def test_stochastic_density_and_physical_units():
    omega = np.linspace(0.1, 20.0, 50)
    assert np.allclose(stochastic.kt_cp_psd(omega, 2.5, 0.6, 0.25, 0.6, 1.3),
                       kt_cp_reference(omega, 2.5, 0.6, 0.25, 0.6, 1.3), rtol=1e-14)
    length, omega_ax = 0.02, 2.0 * math.pi * 1.2
    si = {"omega_g": 15.6, "zeta_g": 0.6, "omega_f": 1.5, "zeta_f": 0.6, "intensity": 0.01,
          "dt": 0.01, "duration": 20.0, "seed": 3}
    model = stochastic.model_parameters(si, length, omega_ax)
    w = np.linspace(0.5, 60.0, 30)  # rad/s
    s_si = kt_cp_reference(w, 15.6, 0.6, 1.5, 0.6, 0.01)
    s_model = stochastic.kt_cp_psd(w / omega_ax, model["omega_g"], 0.6, model["omega_f"], 0.6,
                                   model["intensity"])
    assert np.allclose(s_model, s_si / (length**2 * omega_ax**3), rtol=1e-13)
    assert model["dt"] == pytest.approx(0.01 * omega_ax)


# --------------------------------------------------------------- inside a kernel
def carried_walk(module):
    """A compiled loop using the module as an engine would: carried state, at, next_kink."""
    anchor, shifted, at_anchor, at, kink = (module.anchor, module.shifted, module.at_anchor,
                                            module.at, module.next_kink)

    @njit
    def walk(p, base, t0, h, out):
        c0, c1 = anchor(t0, p, base)
        for k in range(out.shape[0]):
            d0, d1 = shifted(c0, c1, (k + 1) * h, p, base)  # one shift from the anchor (DOPRI)
            u, v = at_anchor(d0, d1, p, base)
            u_ref, v_ref = at(t0 + (k + 1) * h, p, base)
            out[k, 0] = u - u_ref
            out[k, 1] = v - v_ref
            out[k, 2] = kink(t0 + k * h, p, base)

    return walk


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.NAME)
def test_carried_state_in_a_kernel(module):
    times, accel = random_record(8, 80, uniform=True)
    blocks = {"sine": sine.block({"period_ratio": 0.8}), "none": none.block({}),
              "record": record.block_from_samples(times, accel),
              "stochastic": stochastic.block({**SPEC, "duration": 20.0})}
    p = np.concatenate([[np.nan, np.nan], blocks[module.NAME]])
    out = np.empty((40, 3))
    carried_walk(module)(p, 2, 1.3, 0.007, out)
    assert np.max(np.abs(out[:, :2])) < 1e-13
    if module.KINKS:
        assert np.all(np.isfinite(out[:, 2])) and np.all(out[:, 2] > 1.3)
    else:
        assert np.all(np.isinf(out[:, 2]))


def test_stochastic_covariances_match_the_density():
    """The exact recursion against integrals of the closed-form density (mpmath).

    R(tau) = 2 int_0^inf S(w) cos(w tau) dw must equal c Phi^m P c^T at tau = m dt,
    and P must be stationary under the recursion: P = Phi P Phi^T + Q.
    """
    mpmath = pytest.importorskip("mpmath")
    wg, zg, wf, zf, s0, dt = 2.5, 0.6, 0.25, 0.6, 1.0, 0.1
    phi, q_factor, p_factor, c = stochastic.discretisation(wg, zg, wf, zf, s0, dt)
    cov = p_factor @ p_factor.T
    stationary = phi @ cov @ phi.T + q_factor @ q_factor.T
    assert np.allclose(stationary, cov, rtol=0.0, atol=1e-12 * abs(cov).max())

    def density(w):
        return kt_cp_reference(w, mpmath.mpf(wg), zg, wf, zf, s0)

    for m in (0, 1, 7, 30):
        tau = m * dt
        with mpmath.workdps(20):
            if m == 0:
                exact = 2 * mpmath.quad(density, [0, wf, wg, 10 * wg, mpmath.inf])
            else:
                exact = 2 * mpmath.quadosc(lambda w, tau=tau: density(w) * mpmath.cos(w * tau),
                                           [0, mpmath.inf], omega=tau)
        model = c @ np.linalg.matrix_power(phi, m) @ cov @ c
        assert model == pytest.approx(float(exact), rel=1e-8, abs=1e-9), m


def test_stochastic_envelope_variance():
    """Ensemble variance of Jennings-modulated realisations = e(t)^2 sigma^2, within its error."""
    realisations = 1000
    spec = {**SPEC, "duration": 40.0, "envelope": "jennings", "t_rise": 5.0,
            "t_plateau": 15.0, "decay": 0.1}
    runs = np.array([stochastic.generate({**spec, "seed": 50_000 + i})[1]
                     for i in range(realisations)])
    _, _, p_factor, c = stochastic.discretisation(2.5, 0.6, 0.25, 0.6, 1.0, SPEC["dt"])
    sigma2 = c @ p_factor @ p_factor.T @ c
    t = np.arange(runs.shape[1]) * SPEC["dt"]
    expected = stochastic.envelope(t, spec) ** 2 * sigma2
    keep = expected > 0.0
    z = (runs[:, keep] ** 2).mean(axis=0) / expected[keep] - 1.0
    z *= math.sqrt(realisations / 2.0)  # a^2 / var is chi-square(1): variance 2
    assert abs(z.mean()) < 5.0 / math.sqrt(keep.sum() / 20.0) and np.max(np.abs(z)) < 5.5
