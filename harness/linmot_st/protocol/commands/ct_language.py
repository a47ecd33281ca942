"""The command-table language ([MC] 4.3.124..127, 4.3.166..167, 4.3.173..211, [MC] 6; seed 004 TOC 4.3.120..123,
4.3.144..189): modify an entry in RAM, the waits on a position, velocity or current level, the two variables and
the IF jumps, and the VAI to a variable's position. Layouts from [MC] 4.3 (spec/linmot-motion-commands.md rows
120..123, 144..189). What each does is emulator/linmot/motion/ct_language.py's; the waits hold only a command-table
sequence (Kind.WAIT, ct_runner.py).

Left out: 213xh/214xh (the trigger waits: the triggered group's rows, protocol/commands/triggered.py); the [MC]-only 218xh/219xh, 24Exh, 256xh/257xh (named in the overview 4.2 only, no layout) and 266xh
(the master encoder's counts)."""

from __future__ import annotations

from .row import CommandDef, Field, Kind, Start, register

MODIFY_CT_16BIT, MODIFY_CT_32BIT = 0x208, 0x209
WAIT_DEMAND_POS_GREATER, WAIT_DEMAND_POS_LESS = 0x220, 0x221
WAIT_ACTUAL_POS_GREATER, WAIT_ACTUAL_POS_LESS = 0x222, 0x223
WAIT_DIFF_POS_GREATER, WAIT_DIFF_POS_LESS = 0x224, 0x225
WAIT_DIFF_POS_UNSIGNED_GREATER, WAIT_DIFF_POS_UNSIGNED_LESS = 0x226, 0x227
WAIT_DEMAND_VEL_GREATER, WAIT_DEMAND_VEL_LESS = 0x228, 0x229
WAIT_ACTUAL_VEL_GREATER, WAIT_ACTUAL_VEL_LESS = 0x22A, 0x22B
WAIT_CURRENT_GREATER, WAIT_CURRENT_LESS = 0x22E, 0x22F
SET_CT_VAR1, ADD_CT_VAR1, SET_CT_VAR2, ADD_CT_VAR2 = 0x240, 0x241, 0x242, 0x243
CT_VAR1_TO_UPID, CT_VAR2_TO_UPID, UPID_TO_CT_VAR1, UPID_TO_CT_VAR2 = 0x248, 0x249, 0x24C, 0x24D
IF_VAR1_LESS, IF_VAR1_GREATER, IF_VAR2_LESS, IF_VAR2_GREATER = 0x250, 0x251, 0x252, 0x253
IF_DEMAND_POS_LESS, IF_DEMAND_POS_GREATER = 0x258, 0x259
IF_ACTUAL_POS_LESS, IF_ACTUAL_POS_GREATER = 0x25A, 0x25B
IF_DIFF_POS_LESS, IF_DIFF_POS_GREATER = 0x25C, 0x25D
IF_CURRENT_LESS, IF_CURRENT_GREATER = 0x25E, 0x25F
IF_ANALOG_X4_4_LESS = 0x260
IF_MASKED_X4_INPUTS, IF_MASKED_X6_INPUTS = 0x262, 0x263
IF_MASKED_STATUS_WORD, IF_MASKED_WARN_WORD = 0x264, 0x265
VAI_GO_TO_CT_VAR1, VAI_GO_TO_CT_VAR2 = 0x0D4, 0x0D5
VAI_GO_TO_CT_VAR1_FROM_ACT, VAI_GO_TO_CT_VAR2_FROM_ACT = 0x0D6, 0x0D7

_ENTRY = Field("entry", "UINT")
_JUMPS = (Field("if_true", "UINT"), Field("if_false", "UINT"))
_IF_MASKED = (Field("mask", "UINT"), Field("value", "UINT"), *_JUMPS)
_VAD = (Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s2"), Field("dec", "UDINT", "1E-5 m/s2"))


def _wait(cid: int, name: str, unit: str, section: int, type_: str = "DINT") -> CommandDef:
    return CommandDef(cid, name, (Field("level", type_, unit),), Kind.WAIT, source=f"[MC] 4.3.{section}")


def _if(cid: int, name: str, section: int, unit: str = "") -> CommandDef:
    """IF(value) with the entries to continue at; [MC] gives no unit: INFERRED the unit of the same signal's wait."""
    return CommandDef(cid, name, (Field("value", "DINT", unit), *_JUMPS), Kind.CT_IF, source=f"[MC] 4.3.{section}")


register(
    CommandDef(MODIFY_CT_16BIT, "Modify Command Table 16 bit Parameter in RAM",
               (_ENTRY, Field("offset", "UINT", "byte"), Field("value", "INT")), Kind.CT_MODIFY,
               source="[MC] 4.3.166"),
    CommandDef(MODIFY_CT_32BIT, "Modify Command Table 32 bit Parameter in RAM",
               (_ENTRY, Field("offset", "UINT", "byte"), Field("value", "DINT")), Kind.CT_MODIFY,
               source="[MC] 4.3.167"),
    _wait(WAIT_DEMAND_POS_GREATER, "Wait Until Demand Position Greater Than", "0.1 um", 173),
    _wait(WAIT_DEMAND_POS_LESS, "Wait Until Demand Position Less Than", "0.1 um", 174),
    _wait(WAIT_ACTUAL_POS_GREATER, "Wait Until Actual Position Greater Than", "0.1 um", 175),
    _wait(WAIT_ACTUAL_POS_LESS, "Wait Until Actual Position Less Than", "0.1 um", 176),
    _wait(WAIT_DIFF_POS_GREATER, "Wait Until Difference Position Greater Than", "0.1 um", 177),
    _wait(WAIT_DIFF_POS_LESS, "Wait Until Difference Position Less Than", "0.1 um", 178),
    _wait(WAIT_DIFF_POS_UNSIGNED_GREATER, "Wait Until Difference Position Unsigned Greater Than", "0.1 um", 179),
    _wait(WAIT_DIFF_POS_UNSIGNED_LESS, "Wait Until Difference Position Unsigned Less Than", "0.1 um", 180),
    _wait(WAIT_DEMAND_VEL_GREATER, "Wait Until Demand Velocity Greater Than", "1E-6 m/s", 181),
    _wait(WAIT_DEMAND_VEL_LESS, "Wait Until Demand Velocity Less Than", "1E-6 m/s", 182),
    _wait(WAIT_ACTUAL_VEL_GREATER, "Wait Until Actual Velocity Greater Than", "1E-6 m/s", 183),
    _wait(WAIT_ACTUAL_VEL_LESS, "Wait Until Actual Velocity Less Than", "1E-6 m/s", 184),
    _wait(WAIT_CURRENT_GREATER, "Wait Until Current Greater Than", "mA", 185, "INT"),
    _wait(WAIT_CURRENT_LESS, "Wait Until Current Less Than", "mA", 186, "INT"),
    CommandDef(SET_CT_VAR1, "Set Cmd Table Var 1 To", (Field("value", "DINT"),), Kind.CT_VARIABLE,
               source="[MC] 4.3.187"),
    CommandDef(ADD_CT_VAR1, "Add To Cmd Table Var 1", (Field("value", "DINT"),), Kind.CT_VARIABLE,
               source="[MC] 4.3.188"),
    CommandDef(SET_CT_VAR2, "Set Cmd Table Var 2 To", (Field("value", "DINT"),), Kind.CT_VARIABLE,
               source="[MC] 4.3.189"),
    CommandDef(ADD_CT_VAR2, "Add To Cmd Table Var 2", (Field("value", "DINT"),), Kind.CT_VARIABLE,
               source="[MC] 4.3.190"),
    CommandDef(CT_VAR1_TO_UPID, "Write Cmd Table Var 1 To UPID RAM value", (Field("upid", "UINT"),),
               Kind.CT_VARIABLE, source="[MC] 4.3.191"),
    CommandDef(CT_VAR2_TO_UPID, "Write Cmd Table Var 2 To UPID RAM value", (Field("upid", "UINT"),),
               Kind.CT_VARIABLE, source="[MC] 4.3.192"),
    CommandDef(UPID_TO_CT_VAR1, "Write UPID RAM Value To Cmd Table Var 1", (Field("upid", "UINT"),),
               Kind.CT_VARIABLE, source="[MC] 4.3.193"),
    CommandDef(UPID_TO_CT_VAR2, "Write UPID RAM Value To Cmd Table Var 2", (Field("upid", "UINT"),),
               Kind.CT_VARIABLE, source="[MC] 4.3.194"),
    _if(IF_VAR1_LESS, "IF Cmd Table Var 1 Less Than", 195),
    _if(IF_VAR1_GREATER, "IF Cmd Table Var 1 Greater Than", 196),
    # [MC]'s headings of 4.3.197/198 say Var 1; its overview 4.2 and the seed's say Var 2 (spec 1c)
    _if(IF_VAR2_LESS, "IF Cmd Table Var 2 Less Than", 197),
    _if(IF_VAR2_GREATER, "IF Cmd Table Var 2 Greater Than", 198),
    _if(IF_DEMAND_POS_LESS, "IF Demand Position Less Than", 199, "0.1 um"),
    _if(IF_DEMAND_POS_GREATER, "IF Demand Position Greater Than", 200, "0.1 um"),
    _if(IF_ACTUAL_POS_LESS, "IF Actual Position Less Than", 201, "0.1 um"),
    _if(IF_ACTUAL_POS_GREATER, "IF Actual Position Greater Than", 202, "0.1 um"),
    _if(IF_DIFF_POS_LESS, "IF Difference Position Less Than", 203, "0.1 um"),
    _if(IF_DIFF_POS_GREATER, "IF Difference Position Greater Than", 204, "0.1 um"),
    _if(IF_CURRENT_LESS, "IF Current Less Than", 205, "mA"),          # [MC]'s header cell reads 25Cxh (spec 1c)
    _if(IF_CURRENT_GREATER, "IF Current Greater Than", 206, "mA"),
    _if(IF_ANALOG_X4_4_LESS, "IF Analog Val On X4.4 Less Than", 207, "mV"),    # unit INFERRED (as 1DA3h)
    CommandDef(IF_MASKED_X4_INPUTS, "IF Masked X4 Input Value Equal Than", _IF_MASKED, Kind.CT_IF,
               source="[MC] 4.3.208"),
    CommandDef(IF_MASKED_X6_INPUTS, "IF Masked X6 Input Value Equal Than", _IF_MASKED, Kind.CT_IF,
               source="[MC] 4.3.209"),
    CommandDef(IF_MASKED_STATUS_WORD, "IF Masked Status Word Equal Than", _IF_MASKED, Kind.CT_IF,
               source="[MC] 4.3.210"),
    CommandDef(IF_MASKED_WARN_WORD, "IF Masked Warn Word Equal Than", _IF_MASKED, Kind.CT_IF,
               source="[MC] 4.3.211"),
    CommandDef(VAI_GO_TO_CT_VAR1, "VAI Go To Cmd Tab Var1 Pos", _VAD, Kind.VAI_CT_VAR, needs_homing=True,
               source="[MC] 4.3.124"),
    CommandDef(VAI_GO_TO_CT_VAR2, "VAI Go To Cmd Tab Var2 Pos", _VAD, Kind.VAI_CT_VAR, needs_homing=True,
               source="[MC] 4.3.125"),
    CommandDef(VAI_GO_TO_CT_VAR1_FROM_ACT, "VAI Go To Cmd Tab Var1 Pos From Act Pos And Act Vel", _VAD,
               Kind.VAI_CT_VAR, needs_homing=True, start=Start.ACTUAL, source="[MC] 4.3.126"),
    CommandDef(VAI_GO_TO_CT_VAR2_FROM_ACT, "VAI Go To Cmd Tab Var2 Pos From Act Pos And Act Vel", _VAD,
               Kind.VAI_CT_VAR, needs_homing=True, start=Start.ACTUAL, source="[MC] 4.3.127"),
)
