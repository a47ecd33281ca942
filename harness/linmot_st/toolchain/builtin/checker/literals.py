"""Literals: numbers, durations, strings, typed and enumerated literals."""

from __future__ import annotations

import ctypes
import functools
import re

from .. import ast as A
from .. import types as T

FLT_MAX, FLT_MIN = 3.4028234663852886e38, 1.1754943508222875e-38


def outside_float_range(text: str) -> bool:
    """Whether MatIEC rejects this real literal: it reads every real literal with C's strtof (a defect:
    its test of which strtoX to use is always true), whatever the type, and refuses one that sets ERANGE,
    i.e. beyond +-3.4E38 or, non-zero, below 1.18E-38 in magnitude: so even `LREAL#1.0E300`."""
    fn = _strtof()
    if fn is not None:
        ctypes.set_errno(0)
        fn(text.replace("_", "").encode("ascii", "replace"), None)
        return ctypes.get_errno() != 0
    v = abs(float(text.replace("_", "")))     # without a C library: the same bounds, to a rounding
    return v > FLT_MAX or 0 < v < FLT_MIN


@functools.lru_cache(maxsize=1)
def _strtof():
    try:
        fn = ctypes.CDLL(None, use_errno=True).strtof
    except (OSError, AttributeError):
        return None
    fn.restype, fn.argtypes = ctypes.c_float, [ctypes.c_char_p, ctypes.c_void_p]
    return fn


class Literals:
    def check_duration_units(self, e: A.Literal) -> None:
        if re.search(r"(?i)\d(us|ns)", e.text):
            self.error(e.pos, f"{e.text}: the units us and ns are outside the supported subset (MatIEC knows d, h, m, "
                              "s and ms: write T#0.25ms)")

    def infer_Literal(self, e: A.Literal) -> T.Type:
        tn = e.type_name
        if e.kind == "wstring":
            self.error(e.pos, "WSTRING literals are outside the supported subset")
        if e.kind == "time":
            self.check_duration_units(e)
        if e.kind == "string":
            self.check_string_escapes(e)
            self.check_string_ascii(e)
        if e.kind == "string" and tn is not None:
            self.error(e.pos, f"{tn}#{e.text}: a typed string literal is outside the supported subset (MatIEC's "
                              "grammar has no typed string literals and refuses it); write the string alone")
        if e.kind == "real" and outside_float_range(e.text):
            self.error(e.pos, f"the real literal {e.text} is outside the range MatIEC accepts for any real "
                              "literal, LREAL included (it reads them as 32-bit floats: 1.18E-38 to 3.40E38 in "
                              "magnitude, or 0)")
        if tn is None:
            if e.kind == "string":
                return self._string_lit(e)
            return {"int": T.LIT_INT, "real": T.LIT_REAL, "bool": T.BOOL,
                    "time": T.TIME, "date": T.DATE, "tod": T.TOD, "dt": T.DT}[e.kind]
        t = self.named_type_for_literal(tn, e.pos)
        tb = t.base()
        if e.kind == "int":
            if not isinstance(tb, T.Elem) or tb.kind not in ("sint", "uint", "bit", "bool"):
                self.error(e.pos, f"{tn}#{e.text}: an integer is not a {tn} literal")
            lo, hi = (t.lo, t.hi) if isinstance(t, T.Subrange) else (tb.lo, tb.hi)
            if not lo <= e.value <= hi:
                self.error(e.pos, f"the value {e.text} does not fit {tn} ({lo}..{hi})")
            return tb
        if e.kind == "real":
            if tb not in T.REALS:
                self.error(e.pos, f"{tn}#{e.text}: a real number is not a {tn} literal")
            return tb
        if e.kind == "bool":
            if tb is not T.BOOL:
                self.error(e.pos, f"{tn}#{e.text}: not a {tn} literal")
            return T.BOOL
        if e.kind == "string":
            if tb is not T.STRING:
                self.error(e.pos, f"{tn}#{e.text}: not a {tn} literal")
            return self._string_lit(e)
        self.error(e.pos, f"invalid typed literal {tn}#{e.text}")

    def check_string_escapes(self, e: A.Literal) -> None:
        """Escapes that MatIEC turns into C that does not compile or means something else."""
        raw = e.text[1:-1]
        i = 0
        while i < len(raw):
            if raw[i] == "$" and i + 1 < len(raw):
                nxt = raw[i + 1]
                if nxt in "Ll":
                    self.error(e.pos, "the escape $L is outside the supported subset (MatIEC writes a raw line "
                                      "break into the C); use $N")
                # MatIEC writes $N and $hh as C's \xHH, which swallows a hexadecimal digit that follows
                width = 1 if nxt in "Nn" else (2 if re.fullmatch(r"[0-9A-Fa-f]{2}", raw[i + 1:i + 3]) else 0)
                if width and re.match(r"[0-9A-Fa-f]", raw[i + 1 + width:i + 2 + width]):
                    self.error(e.pos, f"'${raw[i + 1:i + 1 + width]}' followed by a hexadecimal digit is outside the "
                                      "supported subset (MatIEC's C reads the digit as part of the escape)")
                i += 1 + max(width, 1)
                continue
            i += 1

    def check_string_ascii(self, e: A.Literal) -> None:
        """MatIEC's lexer takes only 7-bit characters in a string literal (a byte above 127 is no token)."""
        bad = next((ch for ch in e.text if ord(ch) > 127), None)
        if bad is not None:
            self.error(e.pos, f"the string literal contains the non-ASCII character {bad!r}, which MatIEC refuses "
                              "(its lexer knows 7-bit characters only in a string literal); write each byte as "
                              "$hh, e.g. $E9")

    def _string_lit(self, e: A.Literal) -> T.Type:
        if len(e.value) > T.STR_MAX_LEN:
            self.error(e.pos, f"string literal longer than {T.STR_MAX_LEN} characters")
        return T.STRING

    def named_type_for_literal(self, name: str, pos: A.Pos) -> T.Type:
        if name in T.ELEMENTARY:
            return T.ELEMENTARY[name]
        if name in T.ELEMENTARY_ALIASES:
            return T.ELEMENTARY_ALIASES[name]
        if name in self.types:
            return self.types[name]
        self.error(pos, f"unknown type '{name}' in typed literal")

    def infer_EnumLit(self, e: A.EnumLit) -> T.Type:
        t = self.types.get(e.type_name)
        if not isinstance(t, (T.Enum, T.Alias)) or not isinstance(t.base(), T.Enum):
            self.error(e.pos, f"'{e.type_name}' is not an enumerated type")
        en = t.base()
        if e.value.upper() not in en.values:
            self.error(e.pos, f"'{e.value}' is not a value of {en.name}")
        return en
