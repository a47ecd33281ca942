"""The example PVL files shipped in examples/, built in code so that they can be regenerated and are
checked against the files by the tests (`python -m linmot_st.pvl.demo examples/` rewrites them).

- seed_parameters.pvl: the seeds' Figure 13, with the elided MC rows ('……') filled with
  a few parameters of `MC_PARAMETERS` (docs/pvl.md lists which rows were added);
- seed_curve.pvl: the seeds' Figure 14, unchanged;
- two_axes.pvl: what `make demo` commissions onto each of two axes;
- b1100_axis.pvl: a B1100 value list (OS strings, MC parameters; no curves, no command table; docs/pvl.md).

The MC parameter UPIDs are those of the emulated drive's parameter table (emulator/data/), in the MC layer
range 1000h..1EFFh: 1194h (Motor Type) from the seeds; 146Eh/146Fh (min/max position), 1473h (max
position lag) and 14BEh/14BFh (predefined VAI) from the Motion Control SW manual [MC]; the others INVENTED
(docs/upids.md lists every UPID with its source).
"""

from __future__ import annotations

import math
import struct
import sys
from pathlib import Path

from . import codec
from .drive_types import B1100, E1100, DriveType
from .model import CommandTableEntry, Curve, Parameter, ParameterObject, PvlFile
from .writer import write_pvl

OS_TREE = dict(tree_file_name="OSTREE1100OS__V3S0_b1", layer=1, tree_id=1, main_version=3, sub_version=0,
               revision="b1")
MC_TREE = dict(tree_file_name="MCTREE1100DSW4_HC_V3S0_b1", layer=2, tree_id=4612, main_version=3,
               sub_version=0, revision="b1")

CONTROLLER_NAME_UPID = 0x03E8      # stringlets 03E9h..03F0h (seeds Figure 13)
USER_COMMENT_UPID = 0x03F2         # stringlets 03F3h..03FAh (seeds Figure 4 / Table 1)
STRINGLETS_PER_STRING = 8

# (UPID, raw value, caption, scaled value) -- see the module docstring about their origin. The UPIDs,
# captions and limits follow the emulated drive's parameter table (emulator/data/e1100_parameters.csv);
# every value differs from that table's default, so commissioning has something to change.
MC_PARAMETERS = [
    (0x1005, 0x000005DC, r"Motion Control SW\Drive Configuration\Power Bridge\Max Current Limit", "1.5 A"),
    (0x1194, 0x00000002, r"Motion Control SW\Motor Configuration\Motor Type", "P01"),
    (0x11A0, 0x000004B0, r"Motion Control SW\Motor Configuration\Max Current", "1.2 A"),
    (0x13A2, 0x0000000C, r"Motion Control SW\Position Controller\Control Parameter Set A\P Gain", "0.12 A/mm"),
    (0x13A3, 0x00000003, r"Motion Control SW\Position Controller\Control Parameter Set A\D Gain", "0.03 A/(m/s)"),
    (0x13A5, 0x00000064, r"Motion Control SW\Position Controller\Control Parameter Set A\FF Friction", "0.1 A"),
    (0x146E, 0xFFFE7960, r"Motion Control SW\Position Limits\Negative Limit", "-10 mm"),
    (0x146F, 0x001E8480, r"Motion Control SW\Position Limits\Positive Limit", "200 mm"),
    (0x1472, 0x00004E20, r"Motion Control SW\Position Controller\Position Lag Always Warn Level", "2 mm"),
    (0x1473, 0x0000C350, r"Motion Control SW\Position Controller\Position Lag Always Error Level", "5 mm"),
    (0x14BE, 0x0016E360, r"Motion Control SW\Motion Interface\Predefined VA Interpolator\Maximal Velocity", "1.5 m/s"),
    (0x14BF, 0x001E8480, r"Motion Control SW\Motion Interface\Predefined VA Interpolator\Acceleration", "20 m/s^2"),
    (0x1500, 0x00000003, r"Motion Control SW\State Machine Setup\Homing\Mode", "Mech Stop Negative Search"),
    (0x1502, 0x0000C350, r"Motion Control SW\State Machine Setup\Homing\Initial Position", "5 mm"),
]

# seed_parameters.pvl: the seeds' Motor Type row, then five more rows of MC_PARAMETERS
SEED_MC_UPIDS = (0x1194, 0x11A0, 0x1472, 0x1473, 0x13A2, 0x13A3)

SEED_CURVE_INFO_WORDS = (0x00030046, 0x0004000A, 0x6D617845, 0x5F656C70, 0x76727543, 0x00000065,
                         0x00000000, 0x00170000, 0x00004E20, 0x0005001A, 0x4E200301, 0x00000000,
                         0x42400000, 0x0000000F, 0x00000000, 0x00000000, 0x00000000, 0x00000000)
SEED_CURVE_DATA_WORDS = (0x00000000, 0x000075CA, 0x0001C8F2, 0x0003D090, 0x00064DF8, 0x0008F448,
                         0x000B71B0, 0x000D794E, 0x000ECC76, 0x000F4240)


def string_rows(string_upid: int, caption: str, text: str, drive: DriveType = E1100) -> list[Parameter]:
    """The stringlet rows LinMot-Talk writes for a string parameter (all 8 stringlets)."""
    values = codec.encode_stringlets(text, STRINGLETS_PER_STRING)
    return [Parameter(drive.stringlet_upid(string_upid, k), v, f"{caption}_{k}", codec.stringlet_text(v))
            for k, v in enumerate(values, start=1)]


def os_parameters(controller_name: str, user_comment: str) -> ParameterObject:
    rows = (string_rows(CONTROLLER_NAME_UPID, r"OS\Controller Name", controller_name)
            + string_rows(USER_COMMENT_UPID, r"OS\User Comment", user_comment))
    return ParameterObject(**OS_TREE, parameters=tuple(rows))


def mc_parameters(upids=None) -> ParameterObject:
    rows = [r for r in MC_PARAMETERS if upids is None or r[0] in upids]
    return ParameterObject(**MC_TREE, parameters=tuple(Parameter(*r) for r in rows))


def seed_curve() -> Curve:
    """The seeds' Example_Curve (ID 23), info block and setpoints word for word."""
    block, _ = codec.words_to_bytes(SEED_CURVE_INFO_WORDS, codec.INFO_BLOCK_SIZE)
    return Curve(block, tuple(codec.to_signed32(w) for w in SEED_CURVE_DATA_WORDS))


def minimum_jerk_curve(curve_id: int, name: str, stroke: int, duration_10us: int, points: int) -> Curve:
    """A position-vs-time move from 0 to `stroke` (0.1 um) with the minimum-jerk profile
    s(t) = 10t^3 - 15t^4 + 6t^5, machine generated (no wizard)."""
    def s(t: float) -> float:
        return t * t * t * (10 - 15 * t + 6 * t * t)
    values = [round(stroke * s(i / (points - 1))) for i in range(points)]
    return Curve.make(curve_id, name, values, duration_10us)


def cam_curve(curve_id: int, name: str, amplitude: int, length_increments: int, points: int) -> Curve:
    """A cam profile (position vs encoder position): one sine period of +-`amplitude` (0.1 um)."""
    values = [round(amplitude * math.sin(2 * math.pi * i / (points - 1))) for i in range(points)]
    return Curve.make(curve_id, name, values, length_increments, object_type=codec.OBJECT_TYPE_CAM)


def vai_go_to_pos(entry_id: int, name: str, position: int, velocity: int, acceleration: int,
                  deceleration: int, linked_entry: int = codec.CT_NOT_LINKED) -> CommandTableEntry:
    """A CT entry with motion command 010xh VAI Go To Pos: SInt32 position (0.1 um), UInt32 velocity
    (1e-6 m/s), UInt32 acceleration and deceleration (1e-5 m/s^2)."""
    params = struct.pack("<iIII", position, velocity, acceleration, deceleration)
    return CommandTableEntry.make(entry_id, name, 0x0100, params, linked_entry)


def seed_parameters_file() -> PvlFile:
    return PvlFile((os_parameters("MyController", "X Axis Left"), mc_parameters(SEED_MC_UPIDS)))


def seed_curve_file() -> PvlFile:
    return PvlFile((seed_curve(),))


def two_axes_file() -> PvlFile:
    return PvlFile((
        os_parameters("LinMot-ST Demo", "X Axis Left"),
        mc_parameters(),
        seed_curve(),
        minimum_jerk_curve(1, "MinJerk_100mm_400ms", stroke=1_000_000, duration_10us=40_000, points=400),
        cam_curve(2, "Sine_Cam_5mm", amplitude=50_000, length_increments=4096, points=64),
        vai_go_to_pos(1, "Go_Out", 1_000_000, 1_000_000, 1_000_000, 1_000_000, linked_entry=2),
        vai_go_to_pos(2, "Go_Home", 0, 500_000, 1_000_000, 1_000_000),
        vai_go_to_pos(3, "Go_Below_Zero", -50_000, 200_000, 500_000, 500_000),
    ))


# b1100_axis.pvl: the trees of the emulated B1100 (emulator/data/b1100_default.json: names with "B1100", tree IDs
# and versions INVENTED) and UPIDs of its parameter table (b1100_parameters.csv: 7078h User Comment from seed 000
# 2.5, E19Ch Max Current from the CANopen manual p.33 with its example value 3000, 6198h P Gain from LinRS p.26,
# 6300h from seed 004 3.7; the Dxxxh rows are that table's INVENTED UPIDs). Every value differs from the table's.
B1100_OS_TREE = dict(tree_file_name="OSTREEB1100OS_V3S0_b1", layer=1, tree_id=257, main_version=3, sub_version=0,
                     revision="b1")
B1100_MC_TREE = dict(tree_file_name="MCTREEB1100DSW4_V3S0_b1", layer=2, tree_id=4868, main_version=3,
                     sub_version=0, revision="b1")
B1100_CONTROLLER_NAME_UPID = 0x7070   # INVENTED (b1100_parameters.csv)
B1100_USER_COMMENT_UPID = 0x7078      # seed 000 2.5: stringlets 7078h, 7079h, ...
B1100_MC_PARAMETERS = [
    (0x6198, 0x0000000C, r"Motion Control SW\Position Controller\Control Parameter Set A\P Gain", "0.12 A/mm"),
    (0x6300, 0x00000002, r"Motion Control SW\State Machine Setup\Ready To Operate Mode", "Position Controlled"),
    (0xD194, 0x00000002, r"Motion Control SW\Motor Configuration\Motor Type", "P01"),
    (0xD46E, 0xFFFE7960, r"Motion Control SW\Position Limits\Negative Limit", "-10 mm"),
    (0xD46F, 0x001E8480, r"Motion Control SW\Position Limits\Positive Limit", "200 mm"),
    (0xD472, 0x00004E20, r"Motion Control SW\Position Controller\Position Lag Always Warn Level", "2 mm"),
    (0xD473, 0x0000C350, r"Motion Control SW\Position Controller\Position Lag Always Error Level", "5 mm"),
    (0xD4BE, 0x0016E360, r"Motion Control SW\Motion Interface\Predefined VA Interpolator\Maximal Velocity", "1.5 m/s"),
    (0xD502, 0x0000C350, r"Motion Control SW\State Machine Setup\Homing\Initial Position", "5 mm"),
    (0xE19C, 0x00000BB8, r"Motion Control SW\Motor Configuration\Max Current", "3 A"),
]


def b1100_axis_file() -> PvlFile:
    os_rows = (string_rows(B1100_CONTROLLER_NAME_UPID, r"OS\Controller Name", "LinMot-ST B1100", B1100)
               + string_rows(B1100_USER_COMMENT_UPID, r"OS\User Comment", "Y Axis Right", B1100))
    return PvlFile((ParameterObject(**B1100_OS_TREE, parameters=tuple(os_rows)),
                    ParameterObject(**B1100_MC_TREE, parameters=tuple(Parameter(*r) for r in B1100_MC_PARAMETERS))))


EXAMPLES = {
    "seed_parameters.pvl": seed_parameters_file,
    "seed_curve.pvl": seed_curve_file,
    "two_axes.pvl": two_axes_file,
    "b1100_axis.pvl": b1100_axis_file,
}


def main(argv: list[str]) -> int:
    folder = Path(argv[0] if argv else "examples")
    for name, build in EXAMPLES.items():
        (folder / name).write_bytes(write_pvl(build()).encode(codec.TEXT_ENCODING))
        print(folder / name)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
