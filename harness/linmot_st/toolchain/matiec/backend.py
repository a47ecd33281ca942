"""The MatIEC backend as the build driver sees it (toolchain/backend.py's protocol)."""

from __future__ import annotations

import re
from pathlib import Path

from .. import cc
from ..backend import Generated, Rejected
from ..sources import Sources
from . import layout, line_map
from . import tool as iec2c_tool

PACKAGE_DIR = Path(__file__).parent
BUILTIN_DIR = PACKAGE_DIR.parent / "builtin"


class MatiecBackend:
    name = "matiec"
    found_note = "iec2c found"
    missing_note = "iec2c not found"

    def missing(self) -> str | None:
        if iec2c_tool.find() is None:
            return "backend matiec: iec2c not found (set IEC2C or MATIEC_HOME, or put iec2c on PATH)"
        return None

    def available(self) -> bool:
        return self.missing() is None

    def _tool(self) -> iec2c_tool.Matiec:
        tool = iec2c_tool.find()
        if tool is None:
            raise Rejected([f"error: {self.missing()}"])
        return tool

    def version(self) -> str:
        return iec2c_tool.version(self._tool())

    def generator_files(self) -> list[Path]:
        # st_decls reads declarations with the builtin parser: its files shape the MatIEC manifest too
        own = [PACKAGE_DIR / name for name in ("backend.py", "tool.py", "layout.py", "st_decls.py", "line_map.py")]
        return [*own, *sorted(BUILTIN_DIR.glob("*.py")), BUILTIN_DIR / "st.lark"]

    def flags(self) -> list[str]:
        return list(iec2c_tool.flags(self._tool().iec2c)) + unit_flags()

    def generate(self, src: Sources, c_dir: Path, version: str, coverage: bool = False) -> Generated:
        tool = self._tool()
        try:
            manifest, units, plain_units = layout.generate(tool, src, c_dir, version)
        except iec2c_tool.MatiecError as exc:
            raise Rejected(exc.diagnostics) from None
        if coverage:
            # iec2c's C has `#line` already (flags(): `-O l`); made exact per C line and ELSIF
            table = line_map.elsif_table(src.root, list(src.files))
            for c_file in sorted(c_dir.glob("*.c")):
                text = c_file.read_text()
                if "#line" in text:
                    c_file.write_text(line_map.exact_lines(text, table, c_file.name))
        if not trap_flags_supported():
            manifest.setdefault("warnings", []).append(
                "array indices are not checked: the C compiler has no trapping bounds sanitizer")
        elif not cc.checks_undefined_values():
            manifest.setdefault("warnings", []).append(
                "shift counts and REAL -> integer conversions are not checked: the C compiler has no "
                "UBSan shift-exponent/float-cast-overflow checks; where MatIEC's C leaves them undefined "
                "the values are the C compiler's")
        return Generated(manifest, units + plain_units, {u: unit_flags() for u in units}, [c_dir, tool.include],
                         [], list(src.files))

    def explain_c_errors(self, diagnostics: list[str]) -> list[str]:
        return explain_c_errors(diagnostics)


def unit_flags() -> list[str]:
    """Flags of the units iec2c wrote: an index out of range, a shift count out of range and an undefined
    float -> integer conversion stop the scan (the glue reports kinds 2, 6 and 7); and since
    MatIEC sometimes calls a helper it never declares (nor defines), an implicit `int` declaration, which
    would compile into wrong code, is an error at the ST line."""
    return cc.check_flags() + ["-Werror=implicit-function-declaration"]


def trap_flags_supported() -> bool:
    return bool(cc.check_flags())


# a global's accessor (__GET_GLOBAL_X, declared by the CONFIGURATION's VAR_GLOBAL X) is no call wrapper
_MISSING_GLOBAL = re.compile(r"implicit declaration of function .__GET_GLOBAL_(\w+).")
_MISSING_WRAPPER = re.compile(r"implicit declaration of function .__(?!GET_GLOBAL_)\w+?\d+.")


def explain_c_errors(diags: list[str]) -> list[str]:
    """Add what is known about MatIEC defects that surface as C errors."""
    missing = sorted({m[1] for d in diags for m in [_MISSING_GLOBAL.search(d)] if m})
    if missing:
        diags = diags + [
            f"note: no VAR_GLOBAL {', '.join(missing)} in the CONFIGURATION (or no CONFIGURATION at all) for a "
            "VAR_EXTERNAL of that name: iec2c accepts such a VAR_EXTERNAL, but its C then calls __GET_GLOBAL_<name>, "
            "which only the global's declaration provides. Declare the global in the CONFIGURATION built with it."]
    if any(_MISSING_WRAPPER.search(d) for d in diags):
        diags = diags + [
            "note: iec2c used a call wrapper it never defined (MatIEC defect: inside a FUNCTION_BLOCK, a "
            "FUNCTION with VAR_IN_OUT called as an argument of another call, e.g. UDINT_TO_INT(F(Buf, 1)), "
            "gets no wrapper and shifts the numbering of the later ones). Assign such a call's result to a "
            "variable first, then convert it."]
    return diags
