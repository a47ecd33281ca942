"""The row type of the motion-command catalogue and the registry its group modules fill.

A motion command (seed 004 4.1, [MC] 4.3) is one `CommandDef`: its ID (the header's upper 12 bits), name,
parameter layout, the kind of execution (which handler of the drive's interpreter runs it, and so which
variant fields matter), whether it needs the axis homed, the main states that accept it, the drive types that
have it. Rows are registered by the group modules (one per command group of seed 004 4.2); the codec
(`encode`/`decode`), the drive's interpreter and the generated ST encoder read `COMMANDS`.
"""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass

from ..words import OPERATION_ENABLED, STATE_NAMES


class Kind(enum.Enum):
    """How the drive executes a command: one handler of the interpreter per kind."""
    NOP = "no operation"
    CONTROL_WORD = "write the interface control word"
    LIVE_PARAMETER = "write a live parameter"
    MASTER_HOMING = "set the actual position (homing without motion)"
    VAI = "VAI: target, vmax, acc, dec in the command (32 bit)"
    VAI_16BIT = "VAI 16 bit: target, vmax, acc, dec in the 16-bit interface scaling"
    PREDEF_VAI = "predefined VAI: target in the command, vmax/acc/dec from parameters"
    TIME_CURVE = "time curve from the curve RAM"
    COMMAND_TABLE = "command-table control"
    WAIT = "command-table wait (acts only inside a command-table sequence)"
    ENCODER_CAM = "encoder cam: define, enable/disable, go to sync position, set the counter"
    TRIGGERED_CAM = "encoder cam armed on a trigger edge with delay counts"
    POSITION_INDEXING = "encoder position indexing: the target follows the master encoder through a VAI"
    WINDING = "encoder winding: a traverse synchronised to the master's revolutions"
    FORCE_CONTROL = "VAI motion that changes to force control at a force limit"
    IO_OUTPUTS = "write interface outputs with a mask"
    CLEAR_EVENTS = "clear the event handler"
    ON_TRIGGER = "armed in the event handler, run on every trigger edge until 008xh"
    VAI_CAPTURED = "VAI to the captured position plus an increment"
    VAI_ANALOG = "VAI to the position the analog input X4.4 sets"
    VAI_TRIG_CONFIG = "VAI with the Trig Rise / Trig Fall Config parameters"
    PREDEF_VAI_16BIT = "predefined VAI 16 bit: target in the 16-bit scaling, vmax/acc/dec from parameters"
    VAI_PREDEF_ACC = "VAI predef acc: target and vmax in the command, acc/dec from the predefined parameters"
    VAI_DEC_ACC = "VAI dec=acc: target, vmax and one value for acc and dec (and a max current) in the command"
    VAI_16BIT_DEC_ACC = "VAI 16 bit dec=acc: target, vmax, acc=dec in the 16-bit interface scaling"
    SELECT_CONTROLLER_SET = "select the active position-controller set (A/B)"
    RESET = "restart the drive's firmware"
    CT_MODIFY = "modify a parameter of a command-table entry in RAM"
    CT_VARIABLE = "set, add to, store or load a command-table variable"
    CT_IF = "command-table IF: a two-way jump on a condition"
    VAI_CT_VAR = "VAI to the position held in a command-table variable"
    STREAM = "P / PV / PVA stream setpoint with slave-generated time stamp"
    STREAM_STOP = "leave the streaming mode"
    CURVE_MODIFY = "patch a curve's start address, info block or data block in RAM"


class Start(enum.Enum):
    """Where a VAI motion starts (ignored by the other kinds, except TIME_CURVE: see Target)."""
    DEMAND = "demand position and velocity"
    ACTUAL = "actual position and velocity"
    ACTUAL_AT_REST = "actual position, demand velocity 0"
    AFTER_ACTUAL_COMMAND = "queued: from the demand position once the running motion has ended (one shot)"


class Target(enum.Enum):
    """What the position field means (VAI kinds); for TIME_CURVE: FROM_START = the curve's offset is the demand
    position, ABSOLUTE = the offset comes from a field or the curve-offset parameter."""
    ABSOLUTE = "the target position"
    FROM_START = "an increment on the start position"
    FROM_LAST_TARGET = "an increment on the last target"
    STOP = "no target: decelerate to standstill"
    INFINITE_POSITIVE = "no target: to vmax in the positive direction, on until stopped"
    INFINITE_NEGATIVE = "no target: to vmax in the negative direction, on until stopped"
    TRANSITION_POSITIVE = "no target: the running VAI takes the new vmax/acc/dec where the demand passes it upwards"
    TRANSITION_NEGATIVE = "no target: the running VAI takes the new vmax/acc/dec where the demand passes it downwards"
    NONE = "no position"


class Transport(enum.Enum):
    """What the command needs on the project's CANopen mapping (spec/linmot-motion-commands.md, legend
    'bytes'; RxPDO2 carries header + parameter bytes 0..5, RxPDO3 bytes 6..7 by default, up to 6..11
    with 2041h = 2)."""
    RXPDO2 = "fits RxPDO2 alone"
    RXPDO3 = "needs RxPDO3 (parameter bytes 6..11)"
    COMMAND_TABLE = "more than 12 parameter bytes: only as a command-table entry"


RXPDO2_PARAM_BYTES = 6
RXPDO3_PARAM_BYTES_MAX = 12

# IEC type of a field -> struct code (little endian, packed in order after the header)
FIELD_TYPES = {"INT": "h", "UINT": "H", "DINT": "i", "UDINT": "I"}


@dataclass(frozen=True)
class Field:
    name: str
    type: str       # IEC type: INT, UINT, DINT, UDINT
    unit: str = ""  # the drive's unit ('' for IDs, words, counts)

    @property
    def code(self) -> str:
        return FIELD_TYPES[self.type]


# the main states that accept a command from the interface (seed 004 3.7: Operation Enabled; system commands in
# every state of the running MC)
IN_OPERATION_ENABLED = frozenset({OPERATION_ENABLED})
IN_ANY_STATE = frozenset(STATE_NAMES)

E1100, B1100 = "E1100", "B1100"

# seed 004 4.2 (the overview table): the B1100 column has an X for every command of master IDs 00h..03h in
# the seed, except 004xh (X6 outputs) (spec/linmot-b1100.md 3.1); later groups cannot be read from the seed
_SEED_B1100 = frozenset({0x000, 0x001, 0x002, 0x003, 0x008, 0x009, *range(0x010, 0x020), 0x020, 0x021, 0x022,
                         0x023, 0x024, 0x027, 0x028, *range(0x02A, 0x030), 0x030, 0x031, 0x032, 0x03F})


def seed_drives(cid: int) -> frozenset[str]:
    """The drive types that have a command by seed 004's overview: the B1100 only where its column says so."""
    return frozenset({E1100, B1100}) if cid in _SEED_B1100 else frozenset({E1100})


@dataclass(frozen=True)
class CommandDef:
    cid: int
    name: str
    fields: tuple[Field, ...]
    kind: Kind
    needs_homing: bool = False          # sets a position: refused unhomed (settings.motion_requires_homing)
    states: frozenset[int] = IN_OPERATION_ENABLED
    drives: frozenset[str] = frozenset({E1100})
    start: Start = Start.DEMAND
    target: Target = Target.NONE
    source: str = ""                    # where the row comes from ([MC] 4.3.n, seed 004 4.3.n)

    @property
    def format(self) -> str:
        return "<" + "".join(f.code for f in self.fields)

    @property
    def size(self) -> int:
        """Parameter bytes."""
        return struct.calcsize(self.format)

    @property
    def transport(self) -> Transport:
        if self.size <= RXPDO2_PARAM_BYTES:
            return Transport.RXPDO2
        if self.size <= RXPDO3_PARAM_BYTES_MAX:
            return Transport.RXPDO3
        return Transport.COMMAND_TABLE

    @property
    def field_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.fields)


COMMANDS: dict[int, CommandDef] = {}


def register(*rows: CommandDef) -> None:
    """Add rows to the catalogue (group modules at import; a test may add one with monkeypatch.setitem)."""
    for c in rows:
        if c.cid in COMMANDS:
            raise ValueError(f"motion command {c.cid:03X}h registered twice")
        if len(c.fields) > 5:
            raise ValueError(f"{c.cid:03X}h: the ST encoder takes at most 5 parameters (A..E)")
        COMMANDS[c.cid] = c
