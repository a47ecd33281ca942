"""What an emulated drive is made of, loaded from data files: identity, firmware layers with their parameter
trees, the parameter definitions and the error texts. `load_profile()` gives the seeds' example drive
(`load_profile(B1100_PROFILE)` the B1100's data: mixed UPID ranges, stringlets from UPID + 0, no stored
defaults, limits or access rights; seed 000 2.4, 2.5, 3);
`with_tree`, `with_defaults` and `with_parameters` derive other drives (for example one whose MC tree does not
match a configuration, for the commissioning tests)."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field, replace
from pathlib import Path

from .paramtypes import TYPES, ParamType, stringlets_of

DATA_DIR = Path(__file__).parent.parent / "data"      # the drive models' data files
DEFAULT_PROFILE = DATA_DIR / "e1100_default.json"
B1100_PROFILE = DATA_DIR / "b1100_default.json"

# address-usage bits of the UPID list (spec 3.7, INFERRED bit map)
AU_RAM_READ = 1 << 0
AU_RAM_WRITE = 1 << 1
AU_ROM_READ = 1 << 2
AU_ROM_WRITE = 1 << 3
AU_LIVE = 1 << 8
AU_NO_HASH = 1 << 12


class ProfileError(ValueError):
    """A drive profile or parameter file is inconsistent."""


@dataclass(frozen=True)
class ParamDef:
    upid: int
    name: str
    kind: str            # "par", "var", "string" (header of a string; its stringlets are "par" of STRINGLET type)
    type: ParamType
    default: int
    min: int
    max: int
    live: bool
    access: str          # "rw" or "ro"
    layer: int
    stringlets: int = 0  # string header: number of stringlets (E1100 UPID+1 .. UPID+n; B1100 UPID .. UPID+n-1)
    text: str = ""       # string header: default text

    @property
    def address_usage(self) -> int:
        """The UPID list's address-usage word for this entry (spec 3.7)."""
        if self.kind == "string":
            return 0
        if self.kind == "var":
            return AU_RAM_READ | AU_NO_HASH
        au = AU_RAM_READ | AU_ROM_READ
        if self.access == "rw":
            au |= AU_ROM_WRITE
            if self.live:
                au |= AU_RAM_WRITE | AU_LIVE
        return au


@dataclass(frozen=True)
class Layer:
    number: int
    name: str
    upid_first: int | None       # None: the drive's layers have no UPID ranges (B1100: mixed, seed 000 3)
    upid_last: int | None
    tree_file: str
    tree_id: int
    main_version: int
    sub_version: int
    revision: str
    tree_id_upid: int
    main_version_upid: int
    sub_version_upid: int
    # UPIDs a source puts in this layer outside its range (6300h Ready To Operate Mode, seed 004 3.7)
    upid_extra: tuple[int, ...] = ()

    def holds(self, upid: int) -> bool:
        return (self.upid_first is not None and self.upid_first <= upid <= self.upid_last) or upid in self.upid_extra



@dataclass(frozen=True)
class Definitions:
    """How the drive stores its parameter definitions (seed 000 2.4, 2.5, 3). The E1100 stores UPID, RAM/ROM
    location, default, type, min/max and access rights; the B1100 only UPID, RAM/ROM location and type."""
    series: str = "E1100"
    stringlet_offset: int = 1       # stringlet k at string UPID + k - 1 + offset (E1100 1, B1100 0)
    upid_max: int = 0x3FFF          # E1100: 2000h + UPID must be an object of 2000h..5FFFh; B1100: 16 bits
    layer_ranges: bool = True       # each layer has its UPID range (E1100 Table 3); else a layer per CSV row
    stores_defaults: bool = True    # False: the `default` column is the ROM value set at firmware install
    stores_limits: bool = True      # False: no min/max column (any value of the type)
    stores_access_rights: bool = True  # False: no live/access columns (parameters rw, variables ro)


E1100_DEFINITIONS = Definitions()


@dataclass(frozen=True)
class Identity:
    vendor_id: int = 0x156
    article_number: str = "0150-1941"
    revision: int = 0x00030002
    serial: int = 0x0001A2B3
    operating_hours: int = 0
    device_name: str | None = None    # 1008h; None = last 4 characters of the article number ([CO1100])

    @property
    def product_code(self) -> int:
        """1018h sub 2: the last 4 ASCII characters of the article number, first character in the low byte."""
        return int.from_bytes(self.article_number[-4:].encode("ascii"), "little")

    @property
    def name_1008(self) -> str:
        return self.device_name if self.device_name is not None else self.article_number[-4:]


@dataclass(frozen=True)
class DriveProfile:
    identity: Identity
    layers: tuple[Layer, ...]
    parameters: tuple[ParamDef, ...]          # without the generated tree rows and stringlets
    error_texts: dict[int, str] = field(default_factory=dict)
    definitions: Definitions = E1100_DEFINITIONS

    # ---- derived views ----
    def layer(self, number: int) -> Layer:
        for lay in self.layers:
            if lay.number == number:
                return lay
        raise ProfileError(f"no firmware layer {number}")

    def layer_of(self, upid: int) -> int:
        for lay in self.layers:
            if lay.holds(upid):
                return lay.number
        if not self.definitions.layer_ranges:
            for d in self.parameters:
                if d.upid <= upid < d.upid + max(d.stringlets, 1):
                    return d.layer
            if any(upid in self.tree_upids(lay) for lay in self.layers):
                return 1            # the tree info is an OS parameter branch (seed 000 3, Figure 7)
            raise ProfileError(f"UPID {upid:04X}h is not a parameter of this drive (its layers have no ranges)")
        raise ProfileError(f"UPID {upid:04X}h lies in no firmware layer's range")

    @staticmethod
    def tree_upids(lay: Layer) -> tuple[int, int, int]:
        return lay.tree_id_upid, lay.main_version_upid, lay.sub_version_upid

    def stringlet_upid(self, string_upid: int, k: int) -> int:
        """UPID of stringlet k (1, 2, ...) of a string parameter (seed 000 2.5)."""
        return string_upid + k - 1 + self.definitions.stringlet_offset

    def all_definitions(self) -> list[ParamDef]:
        """Every UPID the drive knows: the listed parameters, the stringlets of each string, the tree rows."""
        defs: list[ParamDef] = []
        stringlet = TYPES["STRINGLET"]
        for d in self.parameters:
            defs.append(d)
            if d.kind == "string":
                for k, value in enumerate(stringlets_of(d.text, d.stringlets), start=1):
                    upid = self.stringlet_upid(d.upid, k)
                    if upid == d.upid:      # B1100: stringlet 1 is the string's UPID; the header is not a row
                        defs.pop()
                    defs.append(ParamDef(upid, f"{d.name}_{k}", "par", stringlet, value, 0, 0xFFFFFFFF,
                                         d.live, d.access, self.layer_of(upid)))
        u16 = TYPES["UINT16"]
        for lay in self.layers:
            for upid, what, value in ((lay.tree_id_upid, "Tree ID", lay.tree_id),
                                      (lay.main_version_upid, "Main Version", lay.main_version),
                                      (lay.sub_version_upid, "Sub Version", lay.sub_version)):
                defs.append(ParamDef(upid, f"OS\\Parameter Tree Info\\{lay.name}\\{what}", "par", u16, value,
                                     0, 0xFFFF, False, "ro", self.layer_of(upid)))
        seen: dict[int, str] = {}
        for d in defs:
            if d.upid in seen:
                raise ProfileError(f"UPID {d.upid:04X}h defined twice ({seen[d.upid]!r} and {d.name!r})")
            if not 0 <= d.upid <= self.definitions.upid_max and not any(d.upid in lay.upid_extra for lay in self.layers):
                raise ProfileError(f"UPID {d.upid:04X}h is outside 0000h..{self.definitions.upid_max:04X}h"
                                   + (" (objects 2000h..5FFFh)" if self.definitions.upid_max == 0x3FFF else ""))
            seen[d.upid] = d.name
        return sorted(defs, key=lambda d: d.upid)

    # ---- derived drives ----
    def with_tree(self, layer: int, *, tree_id: int | None = None, main_version: int | None = None,
                  sub_version: int | None = None, tree_file: str | None = None) -> DriveProfile:
        """The same drive with another parameter tree installed in `layer` (1 OS, 2 MC, 3 Interface, 4 Appl)."""
        self.layer(layer)
        changes = {k: v for k, v in dict(tree_id=tree_id, main_version=main_version, sub_version=sub_version,
                                         tree_file=tree_file).items() if v is not None}
        layers = tuple(replace(lay, **changes) if lay.number == layer else lay for lay in self.layers)
        return replace(self, layers=layers)

    def with_defaults(self, defaults: dict[int, int | str]) -> DriveProfile:
        """The same drive with other default (= factory ROM) values for some listed parameters
        (a text for a string header)."""
        known = {d.upid: d for d in self.parameters}
        params = dict(known)
        for upid, value in defaults.items():
            d = known.get(upid)
            if d is None:
                raise ProfileError(f"UPID {upid:04X}h is not a listed parameter")
            if d.kind == "string":
                stringlets_of(str(value), d.stringlets)
                params[upid] = replace(d, text=str(value))
            elif not d.min <= int(value) <= d.max:
                raise ProfileError(f"default {value} of UPID {upid:04X}h outside {d.min} .. {d.max}")
            else:
                params[upid] = replace(d, default=int(value))
        return replace(self, parameters=tuple(params[d.upid] for d in self.parameters))

    def with_parameters(self, defs: list[ParamDef], *, replace_all: bool = False) -> DriveProfile:
        """Add (or, with replace_all, substitute) parameter definitions; a UPID given again replaces the old row."""
        new = {d.upid: d for d in defs}
        base = [] if replace_all else [d for d in self.parameters if d.upid not in new]
        return replace(self, parameters=tuple(sorted(base + list(new.values()), key=lambda d: d.upid)))

    def with_identity(self, **changes) -> DriveProfile:
        return replace(self, identity=replace(self.identity, **changes))


def _int(text: str, what: str, where: str) -> int:
    try:
        return int(text.strip(), 0)
    except ValueError:
        raise ProfileError(f"{where}: {what} {text!r} is not an integer (decimal or 0x-hex)") from None


def _rows(path: Path):
    with path.open(newline="", encoding="utf-8") as f:
        lines = [(n, line) for n, line in enumerate(f, start=1) if line.strip() and not line.lstrip().startswith("#")]
    reader = csv.DictReader([line for _, line in lines])
    for (n, _), row in zip(lines[1:], reader):
        yield f"{path.name}:{n}", row


def load_parameters(path: Path, layer_of, definitions: Definitions = E1100_DEFINITIONS) -> list[ParamDef]:
    """Read a parameter CSV (format: header comment of data/e1100_parameters.csv). A drive without stored
    limits or access rights (`definitions`, data/b1100_parameters.csv) has no min/max or live/access columns
    (parameters are rw and live, variables ro: nothing on the drive could refuse otherwise); a drive whose
    layers have no UPID ranges gives each row's layer in a `layer` column."""
    defs = []
    for where, row in _rows(Path(path)):
        if not definitions.layer_ranges:
            layer = _int(row.get("layer") or "", "layer", where)
            if layer not in (1, 2, 3, 4):
                raise ProfileError(f"{where}: layer {layer} is not 1..4")
            def row_layer(_upid: int, n: int = layer) -> int:
                return n
        else:
            row_layer = layer_of
        if not definitions.stores_access_rights:
            if (row.get("access") or "").strip() or (row.get("live") or "").strip():
                raise ProfileError(f"{where}: this drive stores no access rights: leave out access and live")
            row = dict(row, access="ro" if row["kind"].strip() == "var" else "rw", live="1")
        if not definitions.stores_limits:
            if (row.get("min") or "").strip() or (row.get("max") or "").strip():
                raise ProfileError(f"{where}: this drive stores no min/max: leave them out")
            row = dict(row, min="", max="")
        try:
            upid = int(row["upid"], 16)
            kind = row["kind"].strip()
            tname = row["type"].strip()
            name = row["name"].strip()
        except (KeyError, ValueError, AttributeError):
            raise ProfileError(f"{where}: needs upid (hex), kind, type and name") from None
        if kind not in ("par", "var", "string"):
            raise ProfileError(f"{where}: kind {kind!r} is not par, var or string")
        if tname not in TYPES:
            raise ProfileError(f"{where}: unknown type {tname!r} (known: {', '.join(TYPES)})")
        ptype = TYPES[tname]
        access = row["access"].strip()
        if access not in ("rw", "ro"):
            raise ProfileError(f"{where}: access {access!r} is not rw or ro")
        live = row["live"].strip() == "1"
        if kind == "string":
            if tname != "STRING":
                raise ProfileError(f"{where}: a string row has type STRING")
            count = _int(row["stringlets"], "stringlets", where)
            text = row["default"] or ""
            try:
                stringlets_of(text, count)
            except ValueError as exc:
                raise ProfileError(f"{where}: {exc}") from None
            defs.append(ParamDef(upid, name, kind, ptype, 0, 0, 0, live, access, row_layer(upid), count, text))
            continue
        if tname == "STRING":
            raise ProfileError(f"{where}: type STRING needs kind string")
        lo = _int(row["min"], "min", where) if row["min"].strip() else ptype.lowest
        hi = _int(row["max"], "max", where) if row["max"].strip() else ptype.highest
        default = _int(row["default"], "default", where)
        for what, v in (("min", lo), ("max", hi), ("default", default)):
            if not ptype.lowest <= v <= ptype.highest:
                raise ProfileError(f"{where}: {what} {v} does not fit type {tname}")
        if not lo <= default <= hi:
            raise ProfileError(f"{where}: default {default} outside min {lo} .. max {hi}")
        defs.append(ParamDef(upid, name, kind, ptype, default, lo, hi, live, access, row_layer(upid)))
    return defs


def load_error_texts(path: Path) -> dict[int, str]:
    texts = {}
    for where, row in _rows(Path(path)):
        try:
            code = int(row["code"], 16)
            text = row["text"].strip()
        except (KeyError, ValueError, AttributeError):
            raise ProfileError(f"{where}: needs code (hex) and text") from None
        if len(text) > 32:
            raise ProfileError(f"{where}: error text longer than 32 characters (8 stringlets)")
        texts[code] = text
    return texts


def _identity_and_layers(spec: dict) -> tuple[Identity, tuple[Layer, ...]]:
    ident = spec.get("identity", {})
    identity = Identity(
        vendor_id=int(str(ident.get("vendor_id", "0x156")), 0),
        article_number=str(ident.get("article_number", "0150-1941")),
        revision=int(str(ident.get("revision", "0")), 0),
        serial=int(str(ident.get("serial", "0")), 0),
        operating_hours=int(ident.get("operating_hours", 0)),
        device_name=ident.get("device_name"),
    )
    layers = tuple(Layer(
        number=int(lay["layer"]), name=lay["name"],
        upid_first=int(lay["upid_first"], 16) if "upid_first" in lay else None,
        upid_last=int(lay["upid_last"], 16) if "upid_last" in lay else None,
        tree_file=lay["tree_file"], tree_id=int(lay["tree_id"]), main_version=int(lay["main_version"]),
        sub_version=int(lay["sub_version"]), revision=lay.get("revision", ""),
        tree_id_upid=int(lay["tree_id_upid"], 16), main_version_upid=int(lay["main_version_upid"], 16),
        sub_version_upid=int(lay["sub_version_upid"], 16),
        upid_extra=tuple(int(u, 16) for u in lay.get("upid_extra", ())),
    ) for lay in spec["layers"])
    return identity, layers


def _definitions(spec: dict) -> Definitions:
    """The optional "definitions" object of a profile (E1100 values where absent)."""
    d = spec.get("definitions", {})
    known = {"series", "stringlet_offset", "upid_max", "layer_ranges", "stores_defaults", "stores_limits",
             "stores_access_rights"}
    if unknown := set(d) - known:
        raise ProfileError(f"unknown definitions key(s) {', '.join(sorted(unknown))}")
    e = E1100_DEFINITIONS
    out = Definitions(
        series=str(d.get("series", e.series)),
        stringlet_offset=int(d.get("stringlet_offset", e.stringlet_offset)),
        upid_max=int(str(d.get("upid_max", f"{e.upid_max:04X}")), 16),
        layer_ranges=bool(d.get("layer_ranges", e.layer_ranges)),
        stores_defaults=bool(d.get("stores_defaults", e.stores_defaults)),
        stores_limits=bool(d.get("stores_limits", e.stores_limits)),
        stores_access_rights=bool(d.get("stores_access_rights", e.stores_access_rights)),
    )
    if out.stringlet_offset not in (0, 1) or not 0 < out.upid_max <= 0xFFFF:
        raise ProfileError("definitions: stringlet_offset must be 0 or 1, upid_max 1..FFFF")
    return out


def load_profile(path: str | Path | None = None) -> DriveProfile:
    """Load a drive profile JSON (default: the seeds' example drive, data/e1100_default.json).
    A missing file raises OSError; bad content raises ProfileError naming the file."""
    path = Path(path) if path else DEFAULT_PROFILE
    try:
        spec = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ProfileError(f"{path}:{exc.lineno}: not JSON: {exc.msg}") from None
    except UnicodeDecodeError:
        raise ProfileError(f"{path}: not a UTF-8 text file") from None
    try:
        identity, layers = _identity_and_layers(spec)
        definitions = _definitions(spec)
        parameter_file, error_text_file = spec["parameter_file"], spec.get("error_text_file")
    except ProfileError:
        raise
    except KeyError as exc:
        raise ProfileError(f"{path}: missing key {exc.args[0]!r}") from None
    except (TypeError, ValueError, AttributeError) as exc:
        raise ProfileError(f"{path}: {exc}") from None
    if sorted(lay.number for lay in layers) != [1, 2, 3, 4]:
        raise ProfileError(f"{path.name}: needs the four firmware layers 1..4")
    if definitions.layer_ranges and any(lay.upid_first is None or lay.upid_last is None for lay in layers):
        raise ProfileError(f"{path.name}: every layer needs upid_first and upid_last (or layer_ranges false)")
    probe = DriveProfile(identity, layers, (), definitions=definitions)
    params = load_parameters(path.parent / parameter_file, probe.layer_of, definitions)
    texts = load_error_texts(path.parent / error_text_file) if error_text_file else {}
    profile = DriveProfile(identity, layers, tuple(params), texts, definitions)
    profile.all_definitions()  # validates: no duplicate UPIDs, all in range
    return profile
