"""Operations whose value MatIEC's C leaves undefined: MatIEC's value where its C defines one, a PLC fault
where it does not, on every backend (issue 13, "the values differ").

The expected outcome of each (operation, type, operand) is computed by a model of MatIEC's C written here
from its lib/C headers (iec_std_functions.h __shift_, ROL/ROR; iec_std_lib.h __real_to_sint,
__real_to_uint, TRUNC), so both backends are checked against the same statement of the rule: the builtin
by its own checks, the matiec backend by UBSan's (docs/builtin-compiler.md, "Differences").
"""

from __future__ import annotations

import math

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text

SIGNED = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}
UNSIGNED = {"USINT": 8, "UINT": 16, "UDINT": 32, "ULINT": 64, "BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}
BITS = {"BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}
SHIFT_FAULT, CONV_FAULT = 6, 7

CONVERSIONS = [(f"{src}_TO_{t}", src, t) for src in ("LREAL", "REAL") for t in (*SIGNED, *UNSIGNED)]
TRUNCS = [(f"TRUNC_{t}", "LREAL", t) for t in (*SIGNED, "USINT", "UINT", "UDINT", "ULINT")]
SHIFTS = [(f"{op}_{t}", op, t) for op in ("SHL", "SHR", "ROL", "ROR") for t in BITS]
OPS = [name for name, *_ in CONVERSIONS + TRUNCS + SHIFTS]

REALS = [math.inf, -math.inf, math.nan, 2.5, -2.5, 3.5, -0.4, 300.0, 40000.5, -70000.0, 5e9, -1e10,
         9.2e18, -9.3e18, 1e19]
COUNTS = [-65, -33, -1, 0, 1, 7, 8, 9, 15, 16, 24, 31, 32, 33, 63, 64, 65]


def _program() -> str:
    decls = [f"r_{t} : {t};" for t in (*SIGNED, *UNSIGNED)]
    lines = []
    for i, (name, src, t) in enumerate(CONVERSIONS, 1):
        lines.append(f"    {i}: r_{t} := {name}({'x' if src == 'LREAL' else 'xr'});")
    for i, (_name, _src, t) in enumerate(TRUNCS, len(CONVERSIONS) + 1):
        lines.append(f"    {i}: r_{t} := TRUNC(x);")
    for i, (_name, op, t) in enumerate(SHIFTS, len(CONVERSIONS) + len(TRUNCS) + 1):
        lines.append(f"    {i}: r_{t} := {op}(v_{t}, k);")
    return "\n".join([
        "PROGRAM p_undef",
        "  VAR op : INT; x : LREAL; xr : REAL; k : LINT;",
        "      v_BYTE : BYTE := 16#81; v_WORD : WORD := 16#8001; v_DWORD : DWORD := 16#80000001;",
        "      v_LWORD : LWORD := 16#8000000000000001;",
        "      " + " ".join(decls), "  END_VAR",
        "  CASE op OF", *lines, "  END_CASE;", "END_PROGRAM",
        "CONFIGURATION conf RESOURCE res ON PLC TASK tick(INTERVAL := T#10ms, PRIORITY := 0);",
        "  PROGRAM main WITH tick : p_undef; END_RESOURCE END_CONFIGURATION", ""])


def _wrap(v: int, bits: int, signed: bool) -> int:
    v &= (1 << bits) - 1
    return v - (1 << bits) if signed and v >> (bits - 1) else v


def _lint_round(x: float):
    """MatIEC's __preal_to_sint in LINT: None where C's conversion is undefined."""
    d = x + 0.5 if x >= 0 else x - 0.5
    if math.isnan(d) or not -2.0 ** 63 <= d < 2.0 ** 63:
        return None
    q = int(d)                                   # C truncates toward zero
    if d == math.floor(d) and q % 2:             # an integral d: (q / 2) * 2 in C
        q -= 1 if q > 0 else -1
    return q


def expect_conversion(x: float, target: str):
    if target in SIGNED:
        q = _lint_round(x)
        return ("fault", CONV_FAULT) if q is None else ("value", _wrap(q, SIGNED[target], True))
    if not x >= 0:                              # negative or NaN: MatIEC's __preal_to_uint gives 0
        return ("value", 0)
    q = _lint_round(x)
    return ("fault", CONV_FAULT) if q is None else ("value", _wrap(q, UNSIGNED[target], False))


def expect_trunc(x: float, target: str):
    """MatIEC's TRUNC is a direct C cast to the target: defined when the truncated value fits it."""
    bits, signed = (SIGNED[target], True) if target in SIGNED else (UNSIGNED[target], False)
    lo, hi = (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2 ** bits - 1)
    if math.isnan(x) or math.isinf(x) or not lo <= math.trunc(x) <= hi:
        return ("fault", CONV_FAULT)
    return ("value", math.trunc(x))


def expect_shift(op: str, t: str, v: int, n: int):
    bits = BITS[t]
    c_width = max(32, bits)                      # C shifts BYTE and WORD as int
    mask = (1 << bits) - 1
    if op in ("SHL", "SHR"):
        if n < 0 or n >= c_width:
            return ("fault", SHIFT_FAULT)
        return ("value", ((v << n) if op == "SHL" else (v >> n)) & mask)
    k = n % bits                                 # N %= width, on the count as unsigned long
    if k == 0 and bits == c_width:               # then IN << width (ROL) / IN >> ... << width (ROR)
        return ("fault", SHIFT_FAULT)
    if op == "ROR":
        k = (bits - k) % bits
    return ("value", ((v << k) | (v >> (bits - k))) & mask)


INITIAL = {"BYTE": 0x81, "WORD": 0x8001, "DWORD": 0x80000001, "LWORD": 0x8000000000000001}


def _cases():
    for i, (name, src, t) in enumerate(CONVERSIONS, 1):
        for x in REALS:
            xv = x if src == "LREAL" else _as_real(x)
            yield name, i, {"X" if src == "LREAL" else "XR": x}, t, expect_conversion(xv, t)
    for i, (name, _src, t) in enumerate(TRUNCS, len(CONVERSIONS) + 1):
        for x in REALS:
            yield name, i, {"X": x}, t, expect_trunc(x, t)
    for i, (name, op, t) in enumerate(SHIFTS, len(CONVERSIONS) + len(TRUNCS) + 1):
        for n in COUNTS:
            yield name, i, {"K": n}, t, expect_shift(op, t, INITIAL[t], n)


def _as_real(x: float) -> float:
    import struct
    try:
        return struct.unpack("f", struct.pack("f", x))[0]
    except OverflowError:
        return math.copysign(math.inf, x)


@pytest.fixture(scope="module", params=BACKEND_PARAMS)
def plc(request, tmp_path_factory):
    return Plc(build_text(_program(), tmp_path_factory.mktemp(request.param), request.param))


def _outcome(plc: Plc, op: int, inputs: dict, target: str):
    plc.reset()
    plc["MAIN.OP"] = op
    for var, value in inputs.items():
        plc[f"MAIN.{var}"] = value
    try:
        plc.step(1)
    except PlcFault as fault:
        assert fault.pou == "P_UNDEF", fault
        return ("fault", fault.kind)
    return ("value", plc[f"MAIN.R_{target}"])


@pytest.mark.parametrize("name", sorted(set(OPS)))
def test_matiec_value_or_fault(plc, name):
    wrong = []
    for case_name, op, inputs, target, want in _cases():
        if case_name != name:
            continue
        got = _outcome(plc, op, inputs, target)
        if got != want:
            wrong.append(f"{name}({inputs}): got {got}, MatIEC's C: {want}")
    assert not wrong, "\n".join(wrong)


def test_fault_names_the_operation(plc):
    plc.reset()
    plc["MAIN.OP"] = OPS.index("SHL_DWORD") + 1
    plc["MAIN.K"] = 32
    with pytest.raises(PlcFault, match="SHL/SHR/ROL/ROR count"):
        plc.step(1)
    plc.reset()
    plc["MAIN.OP"] = OPS.index("LREAL_TO_DINT") + 1
    plc["MAIN.X"] = math.nan
    with pytest.raises(PlcFault, match="REAL/LREAL to integer conversion") as info:
        plc.step(1)
    assert info.value.kind == CONV_FAULT and info.value.line > 0
