"""The motion-command catalogue: one row per command (row.py: the row type and the registry), one module per
command group (system, vai, curves, command_table, ...), and the codec both ends use.

Header word = master ID << 8 | sub ID << 4 | count; the command ID is header >> 4 (e.g. 090xh -> 0x090).
Parameters follow the header, little endian; offsets are from the first parameter byte (CANopen "Par Byte n",
= [MC]'s byte offset - 2). The ST encoder F_LmMotionEncode (st_lib/motion/codec_gen.st) is generated from
these rows (`python -m linmot_st.protocol --write`); tests/vectors/motion_commands.json holds encoded examples
both are checked against.

To add a command: one row in its group's module (a new group: a module here and one import line below); a
command of a new kind also needs its handler in emulator/linmot/motion/interpreter.py.
"""

from __future__ import annotations

import struct

from .row import (  # noqa: F401 (the catalogue's API)
    B1100,
    COMMANDS,
    E1100,
    IN_ANY_STATE,
    IN_OPERATION_ENABLED,
    CommandDef,
    Field,
    Kind,
    Start,
    Target,
    Transport,
    register,
)

# the groups register their rows on import, in this order (COMMANDS keeps it; isort leaves it alone); their ID
# constants are the catalogue's names (C.VAI_GO_TO_POS)
# isort: off
from .system import *  # noqa: F401,F403
from .vai import *  # noqa: F401,F403
from .curves import *  # noqa: F401,F403
from .command_table import *  # noqa: F401,F403
from .vai_variants import *  # noqa: F401,F403
from .system_mc import *  # noqa: F401,F403
from .ct_language import *  # noqa: F401,F403
from .io import *  # noqa: F401,F403
from .triggered import *  # noqa: F401,F403
from .encoder_cam import *  # noqa: F401,F403
from .encoder_sync import *  # noqa: F401,F403
from .streams import *  # noqa: F401,F403
from .curve_modify import *  # noqa: F401,F403
# isort: on


def command_id(header: int) -> int:
    return (header >> 4) & 0xFFF


def decode(header: int, params: bytes) -> tuple[CommandDef | None, dict]:
    """The command and its parameter values (missing bytes read as 0); (None, {}) for an unknown command."""
    c = COMMANDS.get(command_id(header))
    if c is None:
        return None, {}
    raw = bytes(params[:c.size]).ljust(c.size, b"\0")
    values = struct.unpack(c.format, raw) if c.fields else ()
    return c, dict(zip(c.field_names, values))


def encode(cid: int, count: int = 0, **values: int) -> bytes:
    """Header and parameters of a command, little endian (tests, tools). An ID the catalogue does not know gets
    its header alone (to provoke 0081h)."""
    header = struct.pack("<H", (cid << 4 | count & 0xF) & 0xFFFF)
    c = COMMANDS.get(cid)
    if c is None:
        return header
    return header + struct.pack(c.format, *(values[n] for n in c.field_names))
