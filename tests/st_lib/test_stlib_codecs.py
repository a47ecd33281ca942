"""The ST library's codec FUNCTIONs on their own (program TB_Codecs of the testbench), against the test
vectors shared with the Python side (tests/vectors/*.json)."""

from __future__ import annotations

import json
import struct

import pytest

from linmot_st.protocol.errors import BY_NAME
from stbench import CODECS, VECTORS, bench_build

E = {name: e.value for name, e in BY_NAME.items()}
STRINGLETS = json.loads((VECTORS / "stringlets.json").read_text())["strings"]
CURVE_VECTORS = json.loads((VECTORS / "curve_info.json").read_text())
CURVES = CURVE_VECTORS["curves"]
LAYOUT = CURVE_VECTORS["layout"]
SDO_VECTORS = VECTORS / "sdo_frames.json"

FIELD_OF = {   # curve_info.json field -> T_LmCurveHeader member
    "data_offset": "DATAOFFSET", "object_type": "OBJECTTYPE", "setpoints": "NUMSETPOINTS",
    "type_size": "TYPESIZE", "curve_id": "CURVEID", "x_length": "XLENGTH", "x_dim_uuid": "XDIMUUID",
    "y_dim_uuid": "YDIMUUID", "wizard_type": "WIZARDTYPE",
}


class Codecs:
    def __init__(self):
        from linmot_st.plc import Plc
        self.plc = Plc(bench_build())

    def __getitem__(self, k):
        return self.plc[f"{CODECS}.{k}"]

    def __setitem__(self, k, v):
        self.plc[f"{CODECS}.{k}"] = v

    def run(self, op: int, **inputs):
        for k, v in inputs.items():
            self[k] = v
        self["OP"] = op
        self.plc.step(1)
        assert self["DONE"] == op and self["OP"] == 0


@pytest.fixture(scope="module")
def c():
    return Codecs()


def name_bytes(text: str, size: int) -> list[int]:
    return list(text.encode("latin-1").ljust(size, b"\0"))


# ---------------------------------------------------------------- stringlets

@pytest.mark.parametrize("vec", STRINGLETS, ids=[s["text"] or "empty" for s in STRINGLETS])
def test_stringlets_pack_and_unpack(c, vec):
    expected = [struct.unpack("<i", struct.pack("<I", int(s["value"], 16)))[0] for s in vec["stringlets"]]
    c.run(1, TEXT=vec["text"], COUNT=vec["count"], STRINGLETS=[7] * 32)
    assert c["ERR"] == 0
    got = c["STRINGLETS"]
    assert got[: vec["count"]] == expected
    assert got[vec["count"]:] == [0] * (32 - vec["count"])       # the rest cleared
    c.run(2, TEXT="junk", COUNT=vec["count"])
    assert c["TEXT"] == vec["text"]


@pytest.mark.parametrize("vec", STRINGLETS, ids=[f'{s.get("drive", "E1100")}-{s["string_upid"]}-{s["text"] or "empty"}'
                                                 for s in STRINGLETS])
def test_stringlet_upids_e1100_and_b1100(c, vec):
    """The shared vectors' UPIDs: E1100 string UPID + k, B1100 the string UPID itself first (seed 000 2.5)."""
    base = int(vec["string_upid"], 16)
    drive = "LM_" + vec.get("drive", "E1100")
    for k, s in enumerate(vec["stringlets"], start=1):
        c.run(4, UPID=base, COUNT=k, DRIVE=drive)
        assert c["UPID"] == int(s["upid"], 16)


def test_stringlet_errors(c):
    c.run(1, TEXT="ABCDEFGHI", COUNT=2)
    assert c["ERR"] == E["TextTooLong"]
    c.run(1, TEXT="ABCDEFGH", COUNT=2)                            # exactly 4 x count: no terminator needed
    assert c["ERR"] == 0
    c.run(1, TEXT="A", COUNT=0)
    assert c["ERR"] == E["InvalidStringletCount"]
    c.run(1, TEXT="A", COUNT=33)
    assert c["ERR"] == E["InvalidStringletCount"]
    c.run(1, TEXT="caf\xe9", COUNT=2)
    assert c["ERR"] == E["InvalidChar"]


def test_every_printable_character_maps_to_its_ascii_code(c):
    for code in range(0x20, 0x7F):
        c.run(3, TEXT="x" + chr(code), POS=2, BYTEIN=code)
        assert c["CODE"] == code, chr(code)
        assert c["CHAROUT"] == chr(code)
    c.run(3, TEXT="ab", POS=3, BYTEIN=0x7F)
    assert c["CODE"] == 0 and c["CHAROUT"] == "?"
    c.run(3, TEXT="\x01", POS=1, BYTEIN=0x00)
    assert c["CODE"] == -1 and c["CHAROUT"] == "?"


def test_name_fields(c):
    c.run(5, TEXT="Example_Curve", CURVENAME=[0xFF] * 22)
    assert c["ERR"] == 0 and c["CURVENAME"] == name_bytes("Example_Curve", 22)
    c.run(6)
    assert c["TEXT"] == "Example_Curve"
    c.run(5, TEXT="x" * 21)
    assert c["ERR"] == 0
    c.run(5, TEXT="x" * 22)                                       # the 22-byte field keeps its 00h
    assert c["ERR"] == E["NameTooLong"]
    c.run(7, TEXT="Sixteen chars ok", CTNAME=[0xFF] * 16)
    assert c["ERR"] == 0 and c["CTNAME"] == name_bytes("Sixteen chars ok", 16)
    c.run(8)
    assert c["TEXT"] == "Sixteen chars ok"
    c.run(7, TEXT="Seventeen chars!!")
    assert c["ERR"] == E["NameTooLong"]


# ---------------------------------------------------------------- curve info block

@pytest.mark.parametrize("vec", CURVES, ids=[v["fields"]["name"] for v in CURVES])
def test_curve_info_parse_and_build(c, vec):
    block = list(bytes.fromhex(vec["info_block"]))
    assert len(block) == 70
    words = b"".join(struct.pack("<I", int(w, 16)) for w in vec["info_words"])
    assert list(words[:70]) == block and words[70:] == bytes.fromhex(vec["pad_bytes"])
    c.run(10, INFO=block)
    h = c["HEADER"]
    f = vec["fields"]
    for key, member in FIELD_OF.items():
        assert h[member] == f[key], key
    assert h["WIZARDPARS"] == f["wizard_params"]
    assert h["NAME"] == name_bytes(f["name"], 22)
    c.run(11, INFO=[0xEE] * 70)                                    # build from the parsed header
    assert c["INFO"] == block
    c.run(12, CURVEID=f["curve_id"], DATASIZE=vec["data_block_size"])
    assert c["ERR"] == 0


def test_curve_info_check_each_fault(c):
    vec = CURVES[0]
    f = vec["fields"]
    good = list(bytes.fromhex(vec["info_block"]))

    def check(mutate=None, curve_id=f["curve_id"], data_size=vec["data_block_size"]):
        c.run(10, INFO=good)
        if mutate:
            h = c["HEADER"]
            mutate(h)
            c["HEADER"] = h
        c.run(12, CURVEID=curve_id, DATASIZE=data_size)
        return c["ERR"]

    assert check() == 0
    assert check(curve_id=0) == E["InvalidCurveId"]
    assert check(curve_id=101) == E["InvalidCurveId"]
    assert check(lambda h: h.update(DATAOFFSET=72)) == E["InfoDataOffset"]
    assert check(lambda h: h.update(OBJECTTYPE=0x0203)) == E["InfoObjectType"]
    assert check(lambda h: h.update(TYPESIZE=2)) == E["InfoTypeSize"]
    assert check(lambda h: h.update(NUMSETPOINTS=1), data_size=4) == E["TooFewSetpoints"]
    assert check(lambda h: h.update(NUMSETPOINTS=1001), data_size=4004) == E["TooManySetpoints"]
    assert check(data_size=vec["data_block_size"] + 4) == E["DataSizeMismatch"]
    assert check(lambda h: h.update(CURVEID=24)) == E["InfoCurveId"]
    assert check(lambda h: h.update(NAME=[0x41] * 22)) == E["NameTooLong"]


def test_curve_header_make_matches_the_seed_layout(c):
    vec = CURVES[1]                                                # the generated cam: no wizard fields
    f = vec["fields"]
    assert f["wizard_type"] == 0
    c.run(13, CURVEID=f["curve_id"], TEXT=f["name"], OBJECTTYPE=f["object_type"], NUMSETPOINTS=f["setpoints"],
          XLENGTH=f["x_length"])
    assert c["ERR"] == 0
    c.run(11)
    assert c["INFO"] == list(bytes.fromhex(vec["info_block"]))
    c.run(13, CURVEID=5, TEXT="t", OBJECTTYPE=0x0003, NUMSETPOINTS=2, XLENGTH=100)
    assert (c["HEADER"]["XDIMUUID"], c["HEADER"]["YDIMUUID"]) == (0x001A, 0x0005)
    c.run(13, CURVEID=5, TEXT="n" * 22, OBJECTTYPE=3, NUMSETPOINTS=2, XLENGTH=100)
    assert c["ERR"] == E["NameTooLong"]


# ---------------------------------------------------------------- command table

def test_ct_build_parse_check(c):
    from linmot_st.emulator import build_entry
    pars = bytes(range(1, 33))
    expected = build_entry(0x0103, pars, name="Go out", link=7)     # the emulator's layout of seeds table 10
    c.run(20, CTFIELDS={"LINK": 7, "HEADER": 0x0103, "PARS": list(pars), "NAME": name_bytes("Go out", 16)},
          CT=[0xEE] * 64)
    assert bytes(c["CT"]) == expected
    c.run(22)
    assert c["ERR"] == 0
    c.run(21, CTFIELDS={"LINK": 0, "HEADER": 0, "PARS": [0] * 32, "NAME": [0] * 16})
    f = c["CTFIELDS"]
    assert (f["LINK"], f["HEADER"], bytes(f["PARS"]), bytes(f["NAME"])) == (7, 0x0103, pars, b"Go out".ljust(16, b"\0"))
    bad = bytearray(expected)
    bad[0] = 0x02
    c.run(22, CT=list(bad))
    assert c["ERR"] == E["CtVersion"]
    bad = bytearray(expected)
    bad[2:4] = (256).to_bytes(2, "little")
    c.run(22, CT=list(bad))
    assert c["ERR"] == E["CtLink"]
    bad[2:4] = b"\xff\xff"
    c.run(22, CT=list(bad))
    assert c["ERR"] == 0


def test_presence_bits(c):
    present = {0, 1, 31, 32, 100, 255}
    words = []
    for k in range(8):
        w = 0xFFFFFFFF
        for n in range(32):
            if 32 * k + n in present:
                w &= ~(1 << n)
        words.append(w)
    c["PRESENCE"] = words
    for entry in list(range(0, 256, 7)) + sorted(present) + [256, 1000]:
        c.run(23, ENTRY=entry)
        assert c["PRESENT"] == (entry in present), entry
    assert c["PRESENTCOUNT"] == len(present)


# ---------------------------------------------------------------- SDO frames and little endian

def test_sdo_request_frames(c):
    c.run(30, INDEX=0x2001, SUBIDX=0x50, VALUE=0x00A40046)          # spec 3.1: add curve 1, info 70, data 164
    assert bytes(c["FRAME"]) == bytes.fromhex("23012050 4600A400")
    c.run(30, INDEX=0x2000, SUBIDX=0x20, VALUE=0x10000000)          # start UPID list at 1000h
    assert bytes(c["FRAME"]) == bytes.fromhex("23002020 00000010")
    c.run(31, INDEX=0x2005, SUBIDX=0x71)
    assert bytes(c["FRAME"]) == bytes.fromhex("40052071 00000000")


def test_sdo_answer_classification(c):
    cases = [
        ("60012050 00000400", "LM_SDO_DOWNLOADED", None),
        ("43002021 0D000410", "LM_SDO_UPLOADED", 0x1004000D),
        ("4B002021 0D000410", "LM_SDO_UPLOADED", 0x0000000D),       # size indicated: 2 bytes
        ("4F002021 0D000410", "LM_SDO_UPLOADED", 0x0000000D & 0xFF),
        ("42002021 0D000410", "LM_SDO_UPLOADED", 0x1004000D),       # expedited, size not indicated
        ("41002021 08000000", "LM_SDO_OTHER", None),                # segmented: not supported
        ("80002021 11000906", "LM_SDO_ABORTED", 0x06090011),
    ]
    for frame, kind, value in cases:
        raw = bytes.fromhex(frame)
        c.run(32, FRAME=list(raw), INDEX=int.from_bytes(raw[1:3], "little"), SUBIDX=raw[3])
        assert c["KIND"] == kind, frame
        assert c["MATCHES"]
        if value is not None:
            assert c["VALUE"] == value, frame
        if kind == "LM_SDO_ABORTED":
            assert c["ABORTCODE"] == value                          # F_LmSdoAbortCode
    c.run(32, FRAME=list(bytes.fromhex("60012051 00000400")), INDEX=0x2001, SUBIDX=0x50)
    assert not c["MATCHES"]


def test_sdo_frames_vectors(c):
    """Every request of the emulator's vectors that the library builds (23h download of 4 bytes, 40h
    upload) is built byte for byte; every response is classified and decoded as the bytes say."""
    data = json.loads(SDO_VECTORS.read_text())
    built = answers = 0
    for v in data["vectors"]:
        for step in v["steps"]:
            req = step.get("request")
            if not req:
                continue
            raw = bytes.fromhex(req)
            if len(raw) != 8:
                continue                    # malformed requests: the library never sends them
            index, sub = struct.unpack_from("<HB", raw, 1)
            if raw[0] == 0x23:
                c.run(30, INDEX=index, SUBIDX=sub, VALUE=struct.unpack_from("<I", raw, 4)[0])
                assert bytes(c["FRAME"]) == raw, (v["name"], step)
                built += 1
            elif raw[0] == 0x40 and not any(raw[4:]):
                c.run(31, INDEX=index, SUBIDX=sub)
                assert bytes(c["FRAME"]) == raw, (v["name"], step)
                built += 1
            resp = step.get("response")
            if not resp:
                continue
            ans = bytes.fromhex(resp)
            c.run(32, FRAME=list(ans), INDEX=index, SUBIDX=sub)
            assert c["MATCHES"] == (ans[1:4] == raw[1:4]), (v["name"], step)
            cs = ans[0]
            if cs == 0x60:
                assert c["KIND"] == "LM_SDO_DOWNLOADED"
            elif cs == 0x80:
                assert c["KIND"] == "LM_SDO_ABORTED"
                assert c["VALUE"] == c["ABORTCODE"] == struct.unpack_from("<I", ans, 4)[0]
            elif cs & 0xF2 == 0x42:
                assert c["KIND"] == "LM_SDO_UPLOADED"
                n = 4 - ((cs >> 2) & 3) if cs & 1 else 4
                assert c["VALUE"] == int.from_bytes(ans[4:4 + n], "little"), (v["name"], step)
            else:
                assert c["KIND"] == "LM_SDO_OTHER", (v["name"], step)
            answers += 1
    assert built > 20 and answers > 20


def test_little_endian_get_put(c):
    frame = list(bytes.fromhex("0102030405060708"))
    for ofs in range(0, 5):
        c.run(33, FRAME=frame, OFS=ofs)
        assert c["U16"] == int.from_bytes(bytes(frame[ofs:ofs + 2]), "little")
        assert c["U32"] == int.from_bytes(bytes(frame[ofs:ofs + 4]), "little")
    c.run(34, FRAME=[0] * 8, OFS=6, U16=0xBEEF)
    assert c["FRAME"] == [0, 0, 0, 0, 0, 0, 0xEF, 0xBE]
    c.run(35, FRAME=[0] * 8, OFS=4, U32=0x01312D00)
    assert c["FRAME"] == [0, 0, 0, 0, 0x00, 0x2D, 0x31, 0x01]


def test_byte_helpers_on_the_curve_vectors_words(c):
    """F_LmU16 / F_LmU32 (bytes -> value, least significant first) and F_LmByteOf (value -> byte n) on the
    info-block words of the shared curve vectors (word k = bytes 4k..4k+3, little endian)."""
    words = [int(w, 16) for vec in CURVES for w in vec["info_words"]] + [0, 0xFFFFFFFF, 0x80000001]
    for w in words:
        raw = w.to_bytes(4, "little")
        for n in range(4):
            c.run(36, B0=raw[0], B1=raw[1], B2=raw[2], B3=raw[3], VALUE=w, BYTEN=n)
            assert c["BYTEOUT"] == raw[n], (hex(w), n)
        assert c["U32"] == w and c["U16"] == w & 0xFFFF, hex(w)


@pytest.mark.parametrize("vec", CURVES, ids=[v["fields"]["name"] for v in CURVES])
def test_info_block_get_and_put_at_the_layout_offsets(c, vec):
    """F_LmInfoGetU16/U32 read every numeric field of the shared vectors' info blocks at its offset of the
    vectors' layout (seeds table 6); F_LmInfoPutU16/U32 of the same fields rebuild the block byte for byte."""
    block = list(bytes.fromhex(vec["info_block"]))
    f = vec["fields"]
    fields = []                                                    # (offset, bits, value)
    for key, ofs, typ in LAYOUT:
        if typ == "UInt16":
            fields.append((ofs, 16, f[key]))
        elif typ == "UInt32":
            fields.append((ofs, 32, f[key]))
        elif typ == "7 x UInt32":
            fields += [(ofs + 4 * i, 32, v) for i, v in enumerate(f[key])]
        else:
            assert typ == "String22" and key == "name"
    assert len(fields) == 16                                        # 9 fields + 7 wizard parameters
    for ofs, bits, value in fields:
        c.run(37, INFO=block, OFS=ofs)
        assert c["U16" if bits == 16 else "U32"] == value, ofs
    c["INFO"] = [0] * 8 + name_bytes(f["name"], 22) + [0] * 40
    for ofs, bits, value in fields:
        if bits == 16:
            c.run(38, OFS=ofs, U16=value)
        else:
            c.run(39, OFS=ofs, U32=value)
    assert c["INFO"] == block


def test_ct_block_get_and_put_u16():
    """F_LmCtGetU16 / F_LmCtPutU16 against the emulator's entry layout (seeds table 10: version A701h,
    link, header, parameters, name): every 16-bit word read back at every offset, and rebuilt by puts."""
    from linmot_st.emulator import build_entry
    from linmot_st.plc import Plc
    c = Codecs.__new__(Codecs)
    c.plc = Plc(bench_build())
    block = build_entry(0x0901, bytes(range(0x80, 0xA0)), name="GoTo 50mm", link=7)
    for ofs in range(0, 63):
        c.run(42, CT=list(block), OFS=ofs)
        assert c["U16"] == int.from_bytes(block[ofs:ofs + 2], "little"), ofs
    c.run(42, OFS=0)
    assert c["U16"] == 0xA701
    c["CT"] = [0xEE] * 64
    for ofs in range(0, 64, 2):
        c.run(43, OFS=ofs, U16=int.from_bytes(block[ofs:ofs + 2], "little"))
    assert bytes(c["CT"]) == block


# ---------------------------------------------------------------- the mailbox

def test_box_append_and_nmt_start(c):
    """F_LmBoxAppend appends after the frames already queued and refuses (TxLost + 1) a 33rd frame;
    F_LmNmtStart appends NMT Start for a node: 000h, 2 bytes, 01h node."""
    c["BOX"] = {"RXCOUNT": 0, "TXCOUNT": 0, "TXLOST": 0}
    c.run(45, NODEID=42)
    assert c["OK"] and c["BOX"]["TXCOUNT"] == 1
    assert c["BOX"]["TX"][0] == {"ID": 0, "DLC": 2, "RTR": False, "DATA": [0x01, 42, 0, 0, 0, 0, 0, 0],
                                 "ECHO": False}
    frame = list(bytes.fromhex("4000201000000000"))
    for n in range(2, 33):
        c.run(44, INDEX=0x600 + n, DLC=8, FRAME=frame)
        assert c["OK"] and c["BOX"]["TXCOUNT"] == n
    assert c["BOX"]["TX"][31] == {"ID": 0x600 + 32, "DLC": 8, "RTR": False, "DATA": frame, "ECHO": False}
    c.run(44, INDEX=0x601, DLC=8, FRAME=frame)
    assert not c["OK"] and (c["BOX"]["TXCOUNT"], c["BOX"]["TXLOST"]) == (32, 1)
    c.run(45, NODEID=1)
    assert not c["OK"] and (c["BOX"]["TXCOUNT"], c["BOX"]["TXLOST"]) == (32, 2)


# ---------------------------------------------------------------- firmware layers

def test_layer_upids_table4(c):
    table = {   # seeds table 4: layer -> (tree ID, main, sub) for E1100 and for B1100
        1: ((0x0539, 0x0532, 0x0533), (0x2CA1, 0x2C96, 0x2C97)),
        2: ((0x0561, 0x055A, 0x055B), (0x2FA1, 0x2F96, 0x2F97)),
        3: ((0x0589, 0x0582, 0x0583), (0x2EA1, 0x2E96, 0x2E97)),
        4: ((0x05B1, 0x05AA, 0x05AB), (0x2DA1, 0x2D96, 0x2D97)),
    }
    for layer, (e1100, b1100) in table.items():
        for what in range(3):
            c.run(40, LAYER=layer, WHAT=what, DRIVE="LM_E1100")
            assert c["UPID"] == e1100[what]
            c.run(40, LAYER=layer, WHAT=what, DRIVE="LM_B1100")
            assert c["UPID"] == b1100[what]
    c.run(40, LAYER=5, WHAT=0, DRIVE="LM_E1100")
    assert c["UPID"] == 0


def test_layer_compatibility_rules_table5(c):
    def check(src, dst):
        c.run(41, SOURCE=dict(zip(("TREEID", "MAINVERSION", "SUBVERSION"), src)),
              TARGET=dict(zip(("TREEID", "MAINVERSION", "SUBVERSION"), dst)))
        return c["ERR"]
    assert check((4612, 3, 0), (4612, 3, 0)) == 0
    assert check((4612, 3, 0), (4612, 3, 2)) == 0                 # source sub version older: fine
    assert check((4612, 3, 3), (4612, 3, 2)) == E["SubVersionNewer"]
    assert check((4612, 2, 0), (4612, 3, 0)) == E["MainVersionMismatch"]
    assert check((4612, 4, 0), (4612, 3, 9)) == E["MainVersionMismatch"]
    assert check((1, 3, 0), (4612, 3, 0)) == E["TreeIdMismatch"]
