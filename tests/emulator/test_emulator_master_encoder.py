"""The master encoder input ([MC] 7.3): the signals that turn it, the counter through the encoder parameters,
the speed filter, and `linmot-st emulate --master-encoder`."""

from __future__ import annotations

import pytest

from linmot_st.emulator.linmot.master_encoder import (
    ConstantSpeed,
    Function,
    MasterEncoder,
    Recorded,
    SpeedProfile,
    parse_signal,
)
from linmot_st.protocol import upids as U

MS = 1_000_000


def encoder(pars: dict | None = None) -> MasterEncoder:
    values = {U.P_MASTER_ENCODER_SOURCE: 1, **(pars or {})}
    return MasterEncoder(lambda upid, default=0: values.get(upid, default))


def test_signals():
    assert ConstantSpeed(-1000, 50).counts(2_000 * MS) == pytest.approx(-1950)
    p = SpeedProfile([(0, 1000), (1000 * MS, -500)], start=10)
    assert p.counts(1000 * MS) == pytest.approx(1010) and p.counts(1500 * MS) == pytest.approx(760)
    assert p.rate(1200 * MS) == -500 and p.counts(-1) == 10
    r = Recorded([(0, 0), (100 * MS, 400), (200 * MS, 400)])
    assert r.counts(50 * MS) == 200 and r.rate(50 * MS) == pytest.approx(4000) and r.rate(150 * MS) == 0
    assert r.counts(10**12) == 400
    f = Function(lambda s: 100 * s * s)
    assert f.counts(2_000 * MS) == pytest.approx(400) and f.rate(2_000 * MS) == pytest.approx(400, rel=1e-4)


def test_counter_decoding_direction_source_and_speed_filter():
    sig = ConstantSpeed(8000)
    e = encoder()
    e.drive_with(sig, 0)
    assert e.counts(500 * MS) == 4000                                 # 4x decoding: every edge counts
    e = encoder({U.P_MASTER_ENCODER_DECODING: 0, U.P_MASTER_ENCODER_DIRECTION: 1})
    e.drive_with(sig, 0)
    assert e.counts(500 * MS) == -1000                                # 1x, negative
    e = encoder({U.P_MASTER_ENCODER_TYPE: 4})                       # step/dir: 4x counts as 2x
    e.drive_with(sig, 0)
    assert e.counts(500 * MS) == 2000
    e = encoder({U.P_MASTER_ENCODER_SOURCE: 0})                     # no source: nothing counts
    e.drive_with(sig, 0)
    assert e.counts(500 * MS) == 0
    e = encoder({U.P_MASTER_ENCODER_SPEED_FILTER: 100})             # 10 ms window
    e.drive_with(SpeedProfile([(0, 8000), (100 * MS, 16000)]), 0)
    assert e.speed(105 * MS) == pytest.approx(12000, rel=0.01)        # half the window at each speed
    assert e.speed(120 * MS) == pytest.approx(16000, rel=0.01)
    e.set_value(-5, 120 * MS)
    assert e.counts(120 * MS) == -5 and e.counts(121 * MS) == 11
    assert e.revolutions(120 * MS + 500 * MS) == pytest.approx((8000 - 5) / 8000, abs=1e-3)


def test_parse_signal(tmp_path):
    assert parse_signal("speed:2500").counts(2_000 * MS) == pytest.approx(5000)
    assert parse_signal("profile:0=1000,1.5=-200").counts(2_000 * MS) == pytest.approx(1400)
    f = tmp_path / "enc.csv"
    f.write_text("# seconds,edges\n0,0\n1,300\n")
    assert parse_signal(f"recorded:{f}").counts(500 * MS) == pytest.approx(150)
    for bad in ("speed:fast", "ramp:1", f"recorded:{tmp_path / 'none.csv'}", "profile:1"):
        with pytest.raises(ValueError):
            parse_signal(bad)


def test_emulate_refuses_a_bad_signal(capsys):
    from linmot_st.cli import main
    rc = main(["emulate", "--interface", "virtual", "--channel", "enc21", "--master-encoder", "speed:x",
               "--duration", "0"])
    assert rc == 2 and "master encoder signal" in capsys.readouterr().err


def test_the_counter_keeps_its_history():
    """A new signal or counter value changes the counter from then on; the counter at earlier times (the
    trajectory record's samples) stays what it was."""
    e = encoder()
    e.drive_with(ConstantSpeed(1000), 0)
    before = [e.counts(t * MS) for t in range(0, 1000, 100)]
    e.drive_with(ConstantSpeed(-4000, t0_ns=1000 * MS), 1000 * MS)
    e.set_value(0, 1500 * MS)
    assert [e.counts(t * MS) for t in range(0, 1000, 100)] == before
    assert e.counts(1000 * MS) == 1000 and e.counts(1250 * MS) == 0 and e.counts(1500 * MS) == 0
    assert e.counts(1600 * MS) == -400 and e.rate(500 * MS) == 1000 and e.rate(1600 * MS) == -4000
