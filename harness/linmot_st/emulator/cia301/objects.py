"""The standard CANopen objects of the E1100 (communication area 1000h..1FFFh; spec 2.1) as a small object
dictionary: value storage with CiA 301 data types, access rights and the checks a write must pass.

The E1100 lists 1000h, 1001h, 1005h, 1006h, 1008h, 1018h and the PDO communication objects 1400h..1402h /
1800h..1802h; 1017h (heartbeat producer time) is added because the heartbeat must be configurable by SDO
(INFERRED, spec gap 3). PDO mapping objects are not offered: the E1100 maps PDOs with LinMot parameters.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field

from .. import codes
from ..codes import SdoAbort

# CiA 301 data types (canopen.objectdictionary.datatypes codes)
BOOLEAN, INTEGER8, INTEGER16, INTEGER32, UNSIGNED8, UNSIGNED16, UNSIGNED32 = 1, 2, 3, 4, 5, 6, 7
VISIBLE_STRING = 9
_FORMATS = {BOOLEAN: "<?", INTEGER8: "<b", INTEGER16: "<h", INTEGER32: "<i",
            UNSIGNED8: "<B", UNSIGNED16: "<H", UNSIGNED32: "<I"}

VAR, RECORD = 7, 9   # CiA 306 object codes


@dataclass
class CommVar:
    index: int
    sub: int
    name: str
    data_type: int
    access: str                          # "ro", "rw", "const"
    default: int | str
    eds_default: str | None = None       # EDS DefaultValue text when it differs (e.g. "$NODEID+0x180")
    check: Callable[[int], bool] | None = None   # value check on writes; False -> abort 06090030
    pre_op_only: bool = False            # writable only in NMT Pre-Operational (PDO COB-IDs, [CO1100] p.18)
    value: int | str = field(default=0, init=False)

    def encode(self) -> bytes:
        if self.data_type == VISIBLE_STRING:
            return str(self.value).encode("latin-1")
        return struct.pack(_FORMATS[self.data_type], self.value)

    @property
    def size(self) -> int | None:
        return None if self.data_type == VISIBLE_STRING else struct.calcsize(_FORMATS[self.data_type])


@dataclass
class CommObject:
    index: int
    name: str
    object_type: int                     # VAR or RECORD
    subs: dict[int, CommVar]


def _cob_id_ok(v: int) -> bool:
    return v & 0x3FFFF800 == 0 and v & 0x7FF != 0        # 11-bit identifier, bit 31 = PDO not valid


def _tx_type_ok(v: int) -> bool:
    return 1 <= v <= 240 or v in (250, 254, 255)


def _rx_type_ok(v: int) -> bool:
    return v in (1, 250, 254, 255)


class CommObjects:
    """Objects 1000h..1FFFh. `reset()` sets the power-on values (NMT Reset Communication)."""

    def __init__(self, node_id: int, identity, heartbeat_ms: Callable[[], int], error_register: Callable[[], int],
                 on_change: Callable[[int, int], None] | None = None):
        self.node_id = node_id
        self._on_change = on_change
        self._heartbeat_default = heartbeat_ms
        self._error_register = error_register
        n = node_id
        objs: list[CommObject] = []

        def var(index, name, dt, access, default, **kw):
            objs.append(CommObject(index, name, VAR, {0: CommVar(index, 0, name, dt, access, default, **kw)}))

        def record(index, name, entries):
            subs = {0: CommVar(index, 0, "Highest sub-index supported", UNSIGNED8, "ro", max(s for s, *_ in entries))}
            for s, sname, dt, access, default, kw in entries:
                subs[s] = CommVar(index, s, sname, dt, access, default, **kw)
            objs.append(CommObject(index, name, RECORD, subs))

        var(0x1000, "Device type", UNSIGNED32, "ro", 0)
        var(0x1001, "Error register", UNSIGNED8, "ro", 0)
        var(0x1005, "COB-ID SYNC", UNSIGNED32, "rw", 0x80, check=lambda v: 0 < v <= 0x7FF)
        var(0x1006, "Communication cycle period", UNSIGNED32, "rw", 0)
        var(0x1008, "Manufacturer device name", VISIBLE_STRING, "const", identity.name_1008)
        var(0x1017, "Producer heartbeat time", UNSIGNED16, "rw", 0)
        record(0x1018, "Identity object", [
            (1, "Vendor-ID", UNSIGNED32, "ro", identity.vendor_id, {}),
            (2, "Product code", UNSIGNED32, "ro", identity.product_code, {}),
            (3, "Revision number", UNSIGNED32, "ro", identity.revision, {}),
            (4, "Serial number", UNSIGNED32, "ro", identity.serial, {}),
        ])
        for k, base in enumerate((0x200, 0x300, 0x400)):
            record(0x1400 + k, f"RxPDO{k + 1} communication parameter", [
                (1, "COB-ID used by RxPDO", UNSIGNED32, "rw", base + n,
                 dict(eds_default=f"$NODEID+0x{base:X}", check=_cob_id_ok, pre_op_only=True)),
                (2, "Transmission type", UNSIGNED8, "rw", 254, dict(check=_rx_type_ok, pre_op_only=True)),
            ])
        for k, base in enumerate((0x180, 0x280, 0x380)):
            record(0x1800 + k, f"TxPDO{k + 1} communication parameter", [
                (1, "COB-ID used by TxPDO", UNSIGNED32, "rw", base + n,
                 dict(eds_default=f"$NODEID+0x{base:X}", check=_cob_id_ok, pre_op_only=True)),
                (2, "Transmission type", UNSIGNED8, "rw", 254, dict(check=_tx_type_ok, pre_op_only=True)),
                (3, "Inhibit time", UNSIGNED16, "rw", 0, dict(pre_op_only=True)),
                (5, "Event timer", UNSIGNED16, "rw", 0, dict(pre_op_only=True)),
            ])
        self.objects: dict[int, CommObject] = {o.index: o for o in objs}
        self.reset()

    def reset(self) -> None:
        for o in self.objects.values():
            for v in o.subs.values():
                v.value = v.default
        self.objects[0x1017].subs[0].value = self._heartbeat_default()

    def entry(self, index: int, sub: int) -> CommVar:
        o = self.objects.get(index)
        if o is None:
            raise SdoAbort(codes.ABORT_NO_OBJECT)
        v = o.subs.get(sub)
        if v is None:
            raise SdoAbort(codes.ABORT_NO_SUBINDEX)
        return v

    def value(self, index: int, sub: int = 0):
        return self.entry(index, sub).value

    def read(self, index: int, sub: int) -> bytes:
        v = self.entry(index, sub)
        if index == 0x1001:
            v.value = self._error_register()
        return v.encode()

    def check_write(self, index: int, sub: int, pre_operational: bool) -> CommVar:
        """The checks that do not need the value (also done when a segmented download starts)."""
        v = self.entry(index, sub)
        if v.access != "rw":
            raise SdoAbort(codes.ABORT_READ_ONLY)
        if v.pre_op_only and not pre_operational:
            raise SdoAbort(codes.ABORT_STATE, "PDO communication parameters change only in Pre-Operational")
        return v

    def write(self, index: int, sub: int, data: bytes, pre_operational: bool) -> CommVar:
        v = self.check_write(index, sub, pre_operational)
        size = v.size
        if size is not None:
            if len(data) > size:
                raise SdoAbort(codes.ABORT_LENGTH_HIGH)
            if len(data) < size:
                raise SdoAbort(codes.ABORT_LENGTH_LOW)
            (value,) = struct.unpack(_FORMATS[v.data_type], data)
        else:
            value = data.decode("latin-1")
        if v.check is not None and not v.check(value):
            raise SdoAbort(codes.ABORT_RANGE)
        v.value = value
        if self._on_change is not None:
            self._on_change(index, sub)
        return v
