"""ProtocolOptions: every alternative answer, checked frame by frame with hand-built raw frames against the drive
served on python-can's `virtual` bus (the defaults are covered by tests/vectors/sdo_frames.json)."""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, ProtocolOptions, build_entry
from linmot_st.emulator.testing import ServedDrive
from shared_vectors import seed_curve

FAST = DriveTimings.fast(boot_ns=2_000_000)
ENTRY = build_entry(0x0101, struct.pack("<iIII", 500_000, 1_000_000, 100_000, 100_000), name="GoTo50mm")
NO_DATA = bytes.fromhex("24 00 00 08")          # abort 08000024h, little endian
NO_SUB = bytes.fromhex("11 00 09 06")           # abort 06090011h
STATE = bytes.fromhex("22 00 00 08")            # abort 08000022h


def served(**options) -> ServedDrive:
    drive = E1100Drive(1, timings=FAST, protocol=ProtocolOptions(**options))
    drive.curves.flash[23] = seed_curve(23)
    drive.ct.flash[5] = ENTRY
    return ServedDrive(drive)


def frame(*parts: bytes | str | int) -> bytes:
    out = b""
    for p in parts:
        out += bytes([p]) if isinstance(p, int) else bytes.fromhex(p) if isinstance(p, str) else p
    assert len(out) == 8, out.hex(" ")
    return out


def test_defaults_are_the_documented_choices():
    assert ProtocolOptions() == ProtocolOptions(curve_read="data32", list_start_result=0x04, ct_prepare_size_at=4,
                                                ct_write="data16_at6", ct_get="rc4_size6", ct_read="rc4_data16",
                                                ct_entry_zero=True, save_refusal="result")
    assert E1100Drive(1).protocol == ProtocolOptions()


@pytest.mark.parametrize("field, value", [("curve_read", "data16"), ("list_start_result", 0xD0),
                                          ("ct_prepare_size_at", 5), ("ct_write", "data32_at6"),
                                          ("ct_get", "rc6_size4"), ("ct_read", "rc4_data32"),
                                          ("ct_entry_zero", 1), ("save_refusal", "D7h"),
                                          ("list_start_result", True)])
def test_bad_option_values_are_refused(field, value):
    with pytest.raises(ValueError, match=f"ProtocolOptions.{field} = "):
        ProtocolOptions(**{field: value})


# ---- 61h / 62h: curve reads ------------------------------------------------------------------------------------

def _curve_reads(layout: str) -> None:
    curve = seed_curve(23)
    with served(curve_read=layout) as s:
        x = s.client.exchange
        assert x("40 17 20 61 00 00 00 00") == frame("80 17 20 61", STATE)          # no 60h yet: any layout
        assert x("40 17 20 60 00 00 00 00") == frame("43 17 20 60 00 46 28 00")     # 60h: unchanged
        for sub, block in ((0x61, curve.info), (0x62, curve.data)):
            req = frame(0x40, "17 20", sub, "00 00 00 00")
            head = frame(0x43, "17 20", sub, "00 00 00 00")[:4]
            step = 4 if layout == "data32" else 2
            for pos in range(0, len(block), step):
                chunk = block[pos:pos + step].ljust(step, b"\0")
                rc = 0x00 if pos + step >= len(block) else 0x04
                want = {"data32": chunk, "rc4_data16": bytes([rc, 0]) + chunk,
                        "data16_rc6": chunk + bytes([rc, 0])}[layout]
                assert x(req) == head + want, (hex(sub), pos)
            after_end = {"data32": frame(0x80, "17 20", sub, NO_DATA),
                         "rc4_data16": head + bytes.fromhex("D0 00 00 00"),
                         "data16_rc6": head + bytes.fromhex("00 00 D0 00")}[layout]
            assert x(req) == after_end


@pytest.mark.parametrize("layout", ["data32", "rc4_data16", "data16_rc6"])
def test_curve_read_layouts(layout):
    _curve_reads(layout)


# ---- 20h / 22h: start of the UPID lists ------------------------------------------------------------------------

@pytest.mark.parametrize("result", [0x04, 0x00])
def test_list_start_result(result):
    with served(list_start_result=result) as s:
        x = s.client.exchange
        assert x("23 00 20 20 00 00 00 10") == frame("60 00 20 20 00 00", result, 0)
        assert x("40 00 20 21 00 00 00 00") == frame("43 00 20 21 0D 00 04 10")        # the list itself: unchanged
        assert x("23 00 20 22 00 00 00 00") == frame("60 00 20 22 00 00", result, 0)


# ---- 83h..86h: command table -----------------------------------------------------------------------------------

def _write_entry(x, entry: int, layout: str, prepare: bytes) -> list[bytes]:
    """Prepare and write ENTRY into `entry` with the 84h layout; returns the answers' result bytes."""
    assert x(frame(0x23, entry, 0x20, 0x83, prepare)) == frame(0x60, entry, 0x20, "83 00 00 00 00")
    step = 4 if layout == "data32" else 2
    results = []
    for pos in range(0, 64, step):
        chunk = ENTRY[pos:pos + step]
        payload = {"data16_at6": b"\0\0" + chunk, "data16_at4": chunk + b"\0\0", "data32": chunk}[layout]
        answer = x(frame(0x23, entry, 0x20, 0x84, payload))
        assert answer[:6] == frame(0x60, entry, 0x20, "84 00 00 00 00")[:6] and answer[7] == 0
        results.append(answer[6])
    return results


@pytest.mark.parametrize("size_at", [4, 6])
def test_ct_prepare_size_position(size_at):
    with served(ct_prepare_size_at=size_at) as s:
        x = s.client.exchange
        good, other = ("40 00 00 00", "00 00 40 00") if size_at == 4 else ("00 00 40 00", "40 00 00 00")
        assert x(frame("23 07 20 83", other)) == frame("60 07 20 83 00 00 D1 00")    # size 0 where it is read
        results = _write_entry(x, 7, "data16_at6", bytes.fromhex(good))
        assert results == [0x04] * 31 + [0x00]
        with s.drive.lock:
            assert s.drive.ct.ram[7] == ENTRY


@pytest.mark.parametrize("layout", ["data16_at6", "data16_at4", "data32"])
def test_ct_write_layouts(layout):
    with served(ct_write=layout) as s:
        x = s.client.exchange
        steps = 16 if layout == "data32" else 32
        assert _write_entry(x, 9, layout, bytes.fromhex("40 00 00 00")) == [0x04] * (steps - 1) + [0x00]
        assert x("23 09 20 84 01 A7 01 A7") == frame("60 09 20 84 00 00 D0 00")    # no block open any more
        with s.drive.lock:
            assert s.drive.ct.ram[9] == ENTRY


@pytest.mark.parametrize("layout", ["rc4_size6", "size16_rc6", "size32"])
def test_ct_get_layouts(layout):
    with served(ct_get=layout) as s:
        x = s.client.exchange
        present = {"rc4_size6": "00 00 40 00", "size16_rc6": "40 00 00 00", "size32": "40 00 00 00"}[layout]
        absent = {"rc4_size6": frame("43 06 20 85 D4 00 00 00"), "size16_rc6": frame("43 06 20 85 00 00 D4 00"),
                  "size32": frame("80 06 20 85", NO_DATA)}[layout]
        assert x("40 05 20 85 00 00 00 00") == frame("43 05 20 85", present)
        assert x("40 06 20 85 00 00 00 00") == absent


@pytest.mark.parametrize("layout", ["rc4_data16", "data16_rc6", "data32"])
def test_ct_read_layouts(layout):
    with served(ct_read=layout) as s:
        x = s.client.exchange
        assert x("40 05 20 86 00 00 00 00") == frame("80 05 20 86", STATE)            # no 85h yet
        assert x("40 05 20 85 00 00 00 00") == frame("43 05 20 85 00 00 40 00")
        step = 4 if layout == "data32" else 2
        for pos in range(0, 64, step):
            chunk = ENTRY[pos:pos + step]
            rc = 0x00 if pos + step >= 64 else 0x04
            want = {"data32": chunk, "rc4_data16": bytes([rc, 0]) + chunk, "data16_rc6": chunk + bytes([rc, 0])}
            assert x("40 05 20 86 00 00 00 00") == frame("43 05 20 86", want[layout]), pos
        after_end = {"data32": frame("80 05 20 86", NO_DATA), "rc4_data16": frame("43 05 20 86 D0 00 00 00"),
                     "data16_rc6": frame("43 05 20 86 00 00 D0 00")}[layout]
        assert x("40 05 20 86 00 00 00 00") == after_end


@pytest.mark.parametrize("zero", [True, False])
def test_ct_entry_zero(zero):
    with served(ct_entry_zero=zero) as s:
        x = s.client.exchange
        if zero:
            assert _write_entry(x, 0, "data16_at6", bytes.fromhex("40 00 00 00"))[-1] == 0x00
            assert x("40 00 20 87 00 00 00 00") == frame("43 00 20 87 DE FF FF FF")   # entries 0 and 5 present
            assert x("40 00 20 85 00 00 00 00") == frame("43 00 20 85 00 00 40 00")
        else:
            # index 2000h has no CT services: entry 0 is answered like curve ID 0
            for sub in (0x82, 0x83, 0x84):
                assert x(frame("23 00 20", sub, "40 00 00 00")) == frame("80 00 20", sub, NO_SUB)
            for sub in (0x85, 0x86):
                assert x(frame("40 00 20", sub, "00 00 00 00")) == frame("80 00 20", sub, NO_SUB)
            assert x("40 00 20 87 00 00 00 00") == frame("43 00 20 87 DF FF FF FF")   # entry 5 present, 0 never
            assert _write_entry(x, 1, "data16_at6", bytes.fromhex("40 00 00 00"))[-1] == 0x00   # entry 1 is the first


@pytest.mark.parametrize("refusal", ["result", "abort"])
def test_flash_save_refusal_with_the_mc_running(refusal):
    with served(save_refusal=refusal) as s:
        x = s.client.exchange
        for sub in (0x40, 0x80):
            want = frame("60 00 20", sub, "00 00 D7 00") if refusal == "result" else frame("80 00 20", sub, STATE)
            assert x(frame("23 00 20", sub, "00 00 00 00")) == want
