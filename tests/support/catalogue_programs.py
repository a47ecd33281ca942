"""What tests in several folders build around the protocol catalogue (protocol/, emulator/motion/, st_lib/motion/):
the ST encoder program around the regenerated F_LmMotionEncode, and the rows issue 20 section 3 added."""

from __future__ import annotations

from pathlib import Path

from linmot_st.protocol import generate
from linmot_st.protocol.commands import system_mc as SYS_ROWS
from linmot_st.protocol.commands import vai_variants as VV_ROWS

# the rows issue 20 section 3 adds (their modules' ID constants)
NEW_ROWS = sorted({v for m in (VV_ROWS, SYS_ROWS) for k, v in vars(m).items() if k.isupper() and isinstance(v, int)})


def encoder_program(tmp_path: Path) -> Path:
    """A program around the regenerated F_LmMotionEncode (with the test's row): the library's image helpers,
    then the generated function, then a program that encodes on every scan."""
    src = tmp_path / "enc.st"
    includes = ["types/can.st", "types/errors.st", "types/lm_types.st", "codecs/le.st", "motion/types.st",
                "motion/codec.st"]
    src.write_text("\n".join(f'{{#include "st_lib/{i}"}}' for i in includes) + "\n" + generate.render_codec() + """
PROGRAM TB_Enc
  VAR
    Cid : UINT;
    Count : USINT;
    A : DINT;
    B : DINT;
    C : DINT;
    D : DINT;
    E : DINT;
    Img : T_LmMotionImage;
    NBytes : USINT;
  END_VAR
  NBytes := F_LmMotionEncode(Cid := Cid, Count := Count, A := A, B := B, C := C, D := D, E := E, Img := Img);
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Enc WITH Main : TB_Enc;
  END_RESOURCE
END_CONFIGURATION
""")
    return src
