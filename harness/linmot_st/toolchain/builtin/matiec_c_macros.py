"""The C macros that MatIEC's generated C cannot hold as a name: the identifiers they take are refused.

iec2c writes an ST name into its C in upper case, unchanged (`data__->EOF`, `typedef ... INT_MAX;`). The C
includes MatIEC's iec_std_lib.h and accessor.h, which include <limits.h>, <float.h>, <math.h>, <stdio.h>...: a
name that one of them defines as an object-like macro is replaced by the preprocessor, and the C no longer
compiles (`EOF : INT` becomes `data__->(-1)`). The list (matiec_c_macros.json) is derived, not guessed: the
preprocessor's own list of macros (`cc -dM -E`) of a unit that includes what MatIEC's C includes, keeping the
object-like macros whose names an ST identifier can spell after iec2c's upper-casing (letters, digits, single
underscores inside) and that do not expand to themselves. Regenerate it with

    python -m linmot_st.toolchain.builtin.matiec_c_macros $MATIEC_HOME/lib/C

tests/toolchain/builtin/test_builtin_matiec_refusals.py derives it again where MatIEC is installed, and shows with iec2c + gcc
that such names break MatIEC's C, in which places.
"""

from __future__ import annotations

import functools
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

from ..cc import find_compiler

DATA = Path(__file__).with_name("matiec_c_macros.json")
# what every unit iec2c writes includes (POUS.h, the POU and resource units)
MATIEC_INCLUDES = ("iec_std_lib.h", "accessor.h")
_DEFINE = re.compile(r"#define (\w+)(\(?)(?: (.*))?$")
# an IEC 61131-3 identifier (no double or trailing underscore) in the upper case iec2c writes
_IEC_UPPER = re.compile(r"(?:[A-Z]|_[A-Z0-9])(?:_?[A-Z0-9])*")


@functools.lru_cache(maxsize=1)
def names() -> frozenset[str]:
    """The stored list: names that cannot be variables, fields, POUs, types or tasks on MatIEC."""
    return frozenset(json.loads(DATA.read_text())["names"])


def derive(include_dir: Path, cc: str = "gcc") -> list[str]:
    """The object-like macros a unit including MatIEC's headers from include_dir sees, that an ST name can hit."""
    unit = "".join(f'#include "{h}"\n' for h in MATIEC_INCLUDES)
    out = subprocess.run([*shlex.split(cc), "-dM", "-E", "-I", str(include_dir), "-x", "c", "-"], input=unit,
                         capture_output=True, text=True, check=True, timeout=120).stdout
    found = set()
    for line in out.splitlines():
        m = _DEFINE.match(line)
        if m and not m[2] and _IEC_UPPER.fullmatch(m[1]) and (m[3] or "").strip() != m[1]:
            found.add(m[1])
    return sorted(found)


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m linmot_st.toolchain.builtin.matiec_c_macros MATIEC_HOME/lib/C", file=sys.stderr)
        return 2
    cc = find_compiler()
    about = ("Object-like C macros that MatIEC's generated C sees (it includes "
             f"{' and '.join(MATIEC_INCLUDES)}, and through them <limits.h>, <float.h>, <math.h>, <stdio.h>...), "
             "whose names an ST identifier can spell in the upper case iec2c writes: as a variable, field, POU, "
             "type or task name, the preprocessor replaces it and the C does not compile. Derived with "
             "`python -m linmot_st.toolchain.builtin.matiec_c_macros $MATIEC_HOME/lib/C` (cc -dM -E), MatIEC HEAD "
             f"of 2024-10, {cc.version}, glibc; another C library may define a few more or fewer.")
    DATA.write_text(json.dumps({"about": about, "names": derive(Path(argv[0]), cc.path)}, indent=1) + "\n")
    print(f"wrote {DATA}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
