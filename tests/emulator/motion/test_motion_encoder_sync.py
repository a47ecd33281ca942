"""Position indexing (070xh..07Fxh) and winding (304xh..311xh) on the emulated E1100: motions that follow the
master encoder ([MC] 4.3.69..72, 4.3.213..216; INFERRED models, docs/emulator.md). Expected positions are
computed here from the parameters and the encoder's counter, not taken from the emulator's plans."""

from __future__ import annotations

import pytest

from linmot_st.emulator import Curve, DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.linmot.master_encoder import ConstantSpeed, Recorded
from linmot_st.emulator.linmot.motion import MotionSettings
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import upids as U

MS = 1_000_000
MM = 10_000


def make_link(values: dict | None = None, **settings) -> MotionLink:
    defaults = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2,
                U.P_MASTER_ENCODER_SOURCE: 1, U.P_MASTER_ENCODER_COUNTS_PER_REV: 8000}
    defaults.update(values or {})
    d = E1100Drive(1, load_profile().with_defaults(defaults), timings=DriveTimings.fast(),
                   motion=MotionSettings(**settings))
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def direct(link, cid: int, **fields) -> None:
    """A command of more than 12 parameter bytes (RxPDO2 + RxPDO3 carry 12; on a real bus it would be a
    command-table entry): straight into the drive's motion command interface, with the next count."""
    link.count = link.count % 15 + 1
    raw = C.encode(cid, link.count, **fields)
    link.drive.mc.command_image(int.from_bytes(raw[:2], "little"), raw[2:], link.t)


def test_position_indexing_steps_with_the_encoder_and_stops():
    link = make_link(position_indexing_pu_per_count=50.0)            # 1000 counts = 5 mm
    mc = link.drive.mc
    here = round(mc.dem_p)
    vmax = 0.2                                                       # m/s
    direct(link, C.START_VAI_ENCODER_POSITION_INDEXING, target=here, vmax=int(vmax * 1e6), acc=500_000,
           dec=500_000)
    t0 = link.t
    # the master indexes 1000 counts at a time, each within 2 ms, every 200 ms: three steps
    steps = [(t0, 0)]
    for k in range(1, 4):
        t = t0 + k * 200 * MS
        steps += [(t, 1000 * (k - 1)), (t + 2 * MS, 1000 * k)]
    mc.encoder.drive_with(Recorded(steps), t0)
    for k in range(1, 4):
        link.run_until(t0 + k * 200 * MS + 190 * MS)
        assert mc.dem_p == pytest.approx(here + k * 5 * MM, abs=1.0), k        # settled on the k-th index
        assert mc.error_code == 0
    samples = mc.trajectory.between(t0, link.t)
    assert max(abs(s.demand_velocity) for s in samples) <= vmax * 1e7 * 1.001
    assert min(s.demand for s in samples) >= here - 1.0                      # no overshoot backwards
    # 07Exh ends indexing and goes to its target; the encoder no longer moves the axis
    direct(link, C.STOP_POSITION_INDEXING_VAI_GO_TO_POS, target=here + 2 * MM, vmax=200_000, acc=500_000,
           dec=500_000)
    link.advance(300 * MS)
    mc.encoder.drive_with(ConstantSpeed(5000, t0_ns=link.t), link.t)
    link.advance(200 * MS)
    assert mc.dem_p == pytest.approx(here + 2 * MM)


def triangle(count: int, start: int, left: float, right: float, pitch: float, cpr: int) -> float:
    travel = max(count - start, 0) / cpr * pitch
    span = right - left
    n, u = divmod(travel, span)
    return left + (u if int(n) % 2 == 0 else span - u)


def test_winding_traverse_reverses_at_its_positions_synchronised_to_revolutions():
    left, right, pitch = 10 * MM, 60 * MM, 25 * MM                   # 2 revolutions per stroke
    link = make_link({U.P_WINDING_LEFT: left, U.P_WINDING_RIGHT: right, U.P_WINDING_PITCH: pitch})
    mc = link.drive.mc
    direct(link, C.VAI_GO_TO_POS, target=left, vmax=200_000, acc=500_000, dec=500_000)
    link.advance(500 * MS)
    link.drive.curves.ram[9] = Curve.build(9, [0, 100], x_length=100, object_type=0x0103)   # a straight stroke
    link.command(C.CURVE_WINDING_START_AT_REVOLUTIONS, curve_id=9, revolutions=1)
    link.advance(2 * MS)
    t0 = link.t
    mc.encoder.drive_with(ConstantSpeed(16_000, t0_ns=t0), t0)      # 2 revolutions/s
    link.advance(2600 * MS)
    enc = mc.encoder
    start = 8000                                                     # the counter was 0: one revolution later
    samples = mc.trajectory.between(t0, link.t)
    for s in samples:
        assert s.demand == pytest.approx(triangle(enc.counts(s.t_ns), start, left, right, pitch, 8000), abs=1e-6)
    # it stood until the start revolution, reversed at the right position after 2 more and at the left after 4
    assert all(s.demand == left for s in samples if enc.counts(s.t_ns) <= start)
    top = max(samples, key=lambda s: s.demand)
    assert top.demand == pytest.approx(right, abs=200) and abs(enc.counts(top.t_ns) - (start + 16_000)) <= 16
    back = [s for s in samples if enc.counts(s.t_ns) > start + 16_000]
    low = min(back, key=lambda s: s.demand)
    assert low.demand == pytest.approx(left, abs=200) and abs(enc.counts(low.t_ns) - (start + 32_000)) <= 16
    assert mc.error_code == 0 and abs(mc.dem_p - mc.axis.position) < 1 * MM


def test_winding_adaptation_commands_are_accepted():
    link = make_link()
    for cid in (C.WINDING_STOP_ADAPTATION, C.WINDING_RESTART_ADAPTATION):
        link.command(cid, 1 * MS)
        link.advance(2 * MS)
        assert link.drive.mc.error_code == 0
    assert link.drive.mc.winding_adaptation is True


def reversals(samples) -> list[float]:
    """The demand at each reversal (a local extreme of the demand)."""
    d = [s.demand for s in samples]
    return [d[i] for i in range(1, len(d) - 1) if (d[i] - d[i - 1]) * (d[i + 1] - d[i]) < 0
            or (d[i] != d[i - 1] and d[i + 1] == d[i])]


def test_winding_adaptation_moves_the_reversal_positions_inwards_until_stopped():
    left, right, pitch = 10 * MM, 60 * MM, 25 * MM
    link = make_link({U.P_WINDING_LEFT: left, U.P_WINDING_RIGHT: right, U.P_WINDING_PITCH: pitch},
                     winding_adaptation_pu_per_stroke=1 * MM)
    mc = link.drive.mc
    direct(link, C.VAI_GO_TO_POS, target=left, vmax=200_000, acc=500_000, dec=500_000)
    link.advance(500 * MS)
    link.drive.curves.ram[9] = Curve.build(9, [0, 100], x_length=100, object_type=0x0103)
    link.command(C.CURVE_WINDING_START, curve_id=9)
    link.advance(2 * MS)
    t0 = link.t
    mc.encoder.drive_with(ConstantSpeed(16_000, t0_ns=t0), t0)      # 2 revolutions/s: 50 mm/s of travel
    link.advance(3500 * MS)                                          # strokes 0..3 (50 + 49 + 47 + 45 mm)
    link.command(C.WINDING_STOP_ADAPTATION)                          # during stroke 3 (it ends at 191 mm)
    link.advance(4000 * MS)
    got = reversals(mc.trajectory.between(t0, link.t))
    # stroke k reverses inwards by 1 mm per stroke adapted before it; stopped from stroke 4 on (4 adapted)
    want = [right, left + 1 * MM, right - 2 * MM, left + 3 * MM, right - 4 * MM, left + 4 * MM, right - 4 * MM]
    assert got[:len(want)] == pytest.approx(want, abs=60), [round(x) for x in got]
    assert mc.error_code == 0


def test_winding_without_a_curve_at_revolutions():
    # 301xh (seed 004 4.3.140, layout INFERRED as 311xh without the curve): a straight traverse that starts at
    # the given revolution, as 311xh with a linear curve would
    link = make_link()
    mc = link.drive.mc
    link.command(C.WINDING_START_AT_REVOLUTIONS, revolutions=2)
    link.advance(2 * MS)
    assert mc.error_code == 0 and 0x301 in [h >> 4 for _, h, _ in mc.executed]
    g = mc.gen
    assert type(g).__name__ == "WindingFollower" and g.shape is None
    assert g.start_count == mc.encoder.counts(g.origin_ns) + 2 * g.cpr
