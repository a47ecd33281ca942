"""The EDS (CiA 306) of the emulated drive, generated from the drive's own object dictionary: the standard
objects of objects.py and the manufacturer objects the SDO server answers (linmot/manufacturer.py), with one record per
UPID. `python -m linmot_st.emulator.cia301.eds [OUT]` writes it (default: data/e1100_co.eds, shipped).

The output is deterministic (no generation date) so that the shipped file can be checked against the code.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..models import make_drive
from . import objects as cm
from .objects import INTEGER32, UNSIGNED8

SHIPPED_EDS = Path(__file__).parent.parent / "data" / "e1100_co.eds"
DATE = "01-01-2025"       # fixed: the file is regenerated only when the object dictionary changes


def _access_of_param_sub(p, sub: int) -> str | None:
    """EDS access of sub 01h..06h of a UPID object; None when the sub offers no access for this UPID."""
    if p.kind == "string":
        return None
    writable = p.kind == "par" and p.access == "rw"
    if sub == 1:
        return "rw" if writable and p.live else "ro"
    if sub == 2:
        return None if p.kind == "var" else ("rw" if writable else "ro")
    if sub in (3, 4, 5):
        return "ro"
    return "wo" if writable and p.live else None


def _index_name(drive, index: int, services) -> str:
    arg = index - 0x2000
    if arg in drive.params:
        p = drive.params[arg]
        return f"UPID {arg:04X}h {p.name}"
    if index == 0x2000:
        return "LinMot system services (and CT entry 0, error log entry 0, error code 00h)"
    scopes = {s.scope for s in services}
    parts = []
    if "curve" in scopes:
        parts.append(f"Curve {arg}")
    if "ct" in scopes:
        parts.append(f"CT entry {arg}")
    if "log" in scopes:
        parts.append(f"Error log entry {arg}")
    if "text" in scopes:
        parts.append(f"Error code {arg:02X}h")
    return ", ".join(parts)


def _clean(text: str) -> str:
    return text.replace(";", ",").replace("\n", " ")


def generate_eds(drive=None) -> str:
    """The EDS text for `drive` (default: the seeds' example drive)."""
    if drive is None:
        drive = make_drive("E1100", 1)
    ident = drive.profile.identity
    lines: list[str] = []

    def section(name: str, items: list[tuple[str, object]]) -> None:
        lines.append(f"[{name}]")
        lines.extend(f"{k}={v}" for k, v in items)
        lines.append("")

    def var(name_section: str, name: str, dtype: int, access: str, default=None, low=None, high=None) -> None:
        items = [("ParameterName", _clean(name)), ("ObjectType", "0x7"), ("DataType", f"0x{dtype:04X}"),
                 ("AccessType", access)]
        if default is not None:
            items.append(("DefaultValue", default))
        if low is not None:
            items += [("LowLimit", low), ("HighLimit", high)]
        items.append(("PDOMapping", 0))
        section(name_section, items)

    section("FileInfo", [
        ("FileName", SHIPPED_EDS.name), ("FileVersion", 1), ("FileRevision", 0), ("EDSVersion", "4.0"),
        ("Description", "LinMot E1100 with CANopen firmware, as emulated by linmot-st (docs/emulator.md)"),
        ("CreationTime", "12:00AM"), ("CreationDate", DATE), ("CreatedBy", "linmot_st.emulator.cia301.eds"),
        ("ModificationTime", "12:00AM"), ("ModificationDate", DATE), ("ModifiedBy", "linmot_st.emulator.cia301.eds"),
    ])
    section("DeviceInfo", [
        ("VendorName", "NTI AG / LinMot"), ("VendorNumber", f"0x{ident.vendor_id:08X}"),
        ("ProductName", "E1100-CO (emulated)"), ("ProductNumber", f"0x{ident.product_code:08X}"),
        ("RevisionNumber", f"0x{ident.revision:08X}"), ("OrderCode", ident.article_number),
        *[(f"BaudRate_{r}", int(r in (125, 250, 500, 1000))) for r in (10, 20, 50, 125, 250, 500, 800, 1000)],
        ("SimpleBootUpMaster", 0), ("SimpleBootUpSlave", 1), ("Granularity", 0),
        ("DynamicChannelsSupported", 0), ("GroupMessaging", 0), ("NrOfRXPDO", 3), ("NrOfTXPDO", 3),
        ("LSS_Supported", 0),
    ])
    comments = [
        "Generated from the emulator's object dictionary (linmot_st.emulator).",
        "Objects 2000h..5FFFh: the sub-index selects the service, the index carries its argument:",
        "2000h+UPID (subs 01h..06h), 2000h+curve ID 1..100 (50h..62h), 2000h+CT entry 0..255 (82h..86h),",
        "2000h+error log entry 0..20 (71h..73h), 2000h+error code 00h..FFh (74h..7Bh), 2000h (system services).",
        "Every manufacturer transfer is expedited with 4 bytes. Download answers carry the E1100 result code",
        "in byte 6. Services marked wo accept any value unless docs/emulator.md gives a layout.",
        "PDO communication objects 1400h..1402h and 1800h..1802h answer SDO but are not listed here: the",
        "E1100 maps its PDOs with LinMot parameters and has no CiA 301 mapping objects.",
    ]
    section("Comments", [("Lines", len(comments))] + [(f"Line{i}", c) for i, c in enumerate(comments, 1)])

    # The PDO communication objects 1400h..1402h / 1800h..1802h are served but not listed: the E1100 maps its
    # PDOs with LinMot parameters, so it has no CiA 301 mapping objects 1600h../1A00h.., and an EDS (and
    # canopen's RemoteNode) may not list a communication object without its mapping object.
    std = sorted(i for i in drive.comm.objects if not 0x1400 <= i <= 0x1BFF)
    mandatory = [i for i in std if i in (0x1000, 0x1001, 0x1018)]
    optional = [i for i in std if i not in mandatory]
    # 2000h+UPID reaches UPIDs 0000h..3FFFh only ([CO1100]); 6300h has no object
    manufacturer = sorted(set(range(0x2000, 0x2100)) | {0x2000 + u for u in drive.params.upids() if u <= 0x3FFF})
    manufacturer = [i for i in manufacturer if drive.mfr.subs_at(i)]
    for name, idx in (("MandatoryObjects", mandatory), ("OptionalObjects", optional),
                      ("ManufacturerObjects", manufacturer)):
        section(name, [("SupportedObjects", len(idx))] + [(str(k), f"0x{i:04X}") for k, i in enumerate(idx, 1)])

    for index in std:
        o = drive.comm.objects[index]
        if o.object_type == cm.VAR:
            v = o.subs[0]
            var(f"{index:04X}", o.name, v.data_type, v.access, v.eds_default or v.default)
            continue
        section(f"{index:04X}", [("ParameterName", o.name), ("ObjectType", "0x9"),
                                 ("SubNumber", f"0x{len(o.subs):X}")])
        for s, v in sorted(o.subs.items()):
            var(f"{index:04X}sub{s:X}", v.name, v.data_type, v.access, v.eds_default or v.default)

    for index in manufacturer:
        services = drive.mfr.subs_at(index)
        arg = index - 0x2000
        p = drive.params[arg] if arg in drive.params else None
        subs: list[tuple[int, tuple]] = []
        for s in services:
            if s.scope == "upid":
                access = _access_of_param_sub(p, s.sub)
                if access is None:
                    continue
                default = {1: p.default, 2: p.default, 3: p.min, 4: p.max, 5: p.default}.get(s.sub)
                limits = (p.min, p.max) if s.sub in (1, 2, 6) and p.max <= 0x7FFFFFFF else (None, None)
                if default is not None and default > 0x7FFFFFFF:
                    default -= 1 << 32              # the SI32 the drive answers
                subs.append((s.sub, (s.name, INTEGER32, access, default, *limits)))
            else:
                subs.append((s.sub, (s.name, s.data_type, s.access, None, None, None)))
        highest = max(x.sub for x in services)
        section(f"{index:04X}", [("ParameterName", _clean(_index_name(drive, index, services))),
                                 ("ObjectType", "0x9"), ("SubNumber", f"0x{len(subs) + 1:X}")])
        var(f"{index:04X}sub0", "Highest sub-index supported", UNSIGNED8, "ro", f"0x{highest:02X}")
        for sub, (name, dtype, access, default, low, high) in subs:
            var(f"{index:04X}sub{sub:X}", name, dtype, access, default, low, high)
    return "\n".join(lines)


def write_eds(path: str | Path = SHIPPED_EDS, drive=None) -> Path:
    path = Path(path)
    path.write_text(generate_eds(drive), encoding="ascii", newline="\r\n")
    return path


if __name__ == "__main__":
    print(write_eds(sys.argv[1] if len(sys.argv) > 1 else SHIPPED_EDS))
