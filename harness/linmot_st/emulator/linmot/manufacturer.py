"""The E1100 manufacturer objects 2000h..5FFFh: the sub-index selects the service, the index carries its
argument (2000h + UPID / curve ID / CT entry / error-log entry / error code), spec 2.2.

Each service is one row of a drive model's service table (`E1100_SERVICES`): its sub-index, scope, and the
handlers that read (upload) and write (download) it; a drive model lists the services its firmware offers
(emulator/models.py). Every transfer is expedited with 4 data bytes. A download answers 60h with the E1100
result code in byte 6 (`int` returned by a write handler, or a `Reply` for services whose answer comes later);
an upload answers 43h with 4 bytes. Requests the drive refuses raise `SdoAbort` (docs/emulator.md lists each
choice).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from .. import codes
from ..cia301.objects import INTEGER32, UNSIGNED32
from ..cia301.sdo import Reply
from ..codes import NoMoreData, NotStarted, SdoAbort
from .params import NotWritable, NoValueAccess, OutOfRange, UnknownUpid
from .paramtypes import stringlets_of

BASE = 0x2000
LAST = 0x5FFF
LIST_END = 0xFFFF


CURVE_IDS = range(1, 101)
LOG_ENTRIES = range(0, 21)        # LinUDP allows entry numbers 0..20 (spec 2.2)


def _le(value: int) -> bytes:
    return (value & 0xFFFFFFFF).to_bytes(4, "little")


def _words(lo: int, hi: int) -> bytes:
    return struct.pack("<HH", lo & 0xFFFF, hi & 0xFFFF)


def read_step(layout: str, read: Callable[[int], tuple[int, bytes]]) -> bytes:
    """Bytes 4..7 of the answer to a read step (61h/62h, 86h) in `layout` (options.py); `read(n)` returns
    (result, the next n bytes) from the store or raises NotStarted / NoMoreData."""
    try:
        if layout == "data32":
            try:
                return read(4)[1]
            except NoMoreData as exc:      # no room for a result next to 4 data bytes
                raise SdoAbort(codes.ABORT_NO_DATA, str(exc)) from None
        try:
            rc, chunk = read(2)
        except NoMoreData:
            rc, chunk = codes.RC_BLOCK_FINISHED, b"\0\0"
    except NotStarted as exc:
        raise SdoAbort(codes.ABORT_STATE, str(exc)) from None
    return bytes([rc, 0]) + chunk if layout == "rc4_data16" else chunk + bytes([rc, 0])


# ---------------------------------------------------------------- the services' handlers
# read(m, arg, sub) -> 4 bytes; write(m, arg, sub, data) -> result code or Reply. `m` is the drive's
# ManufacturerObjects (m.host: the drive), `arg` the index - 2000h, `data` the 4 data bytes of the request.

_UPID_READ = {1: "ram", 2: "rom", 3: "min", 4: "max", 5: "default"}
_UPID_WRITE = {1: (True, False), 2: (False, True), 6: (True, True)}


def _read_upid(m, arg, sub):
    try:
        return _le(m.host.params.read(arg, _UPID_READ[sub]))
    except NoValueAccess as exc:
        raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None


def _write_upid(m, arg, sub, data):
    ram, rom = _UPID_WRITE[sub]
    try:
        m.host.params.write(arg, int.from_bytes(data, "little"), ram=ram, rom=rom)
    except UnknownUpid as exc:   # pragma: no cover - excluded by service()
        raise SdoAbort(codes.ABORT_NO_OBJECT, str(exc)) from None
    except NoValueAccess as exc:
        raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None
    except NotWritable as exc:
        raise SdoAbort(codes.ABORT_READ_ONLY, str(exc)) from None
    except OutOfRange as exc:
        raise SdoAbort(codes.ABORT_RANGE, str(exc)) from None
    return codes.RC_OK


def _set_layer_default(m, arg, sub, data):
    return m.host.set_layer_default(sub - 0x06)


def _reset_drive(m, arg, sub, data):
    return Reply(then=m.host.software_reset)


def _start_list(m, arg, sub, data):
    m.list_cursor[sub == 0x22] = int.from_bytes(data, "little") >> 16
    return m.host.protocol.list_start_result   # 04h: the [CO1100] example (its table says 00h: DOC-ERR)


def _next_list_item(m, arg, sub):
    modified = sub == 0x23
    cursor = m.list_cursor[modified]
    if cursor is None:
        raise SdoAbort(codes.ABORT_STATE, "get next UPID without start (20h/22h)")
    p = m.host.params.next_entry(cursor, modified_only=modified)
    if p is None:
        m.list_cursor[modified] = LIST_END + 1
        return _words(0, LIST_END)
    m.list_cursor[modified] = p.upid + 1
    return _words(p.address_usage, p.upid)


def _stop_mc(m, arg, sub, data):
    return m.host.stop_mc()


def _start_mc(m, arg, sub, data):
    return m.host.start_mc()


def _save_curves(m, arg, sub, data):
    return m.host.save_to_flash("curves")


def _save_ct(m, arg, sub, data):
    return m.host.save_to_flash("ct")


def _poll_flash(m, arg, sub):
    return _le(codes.RC_NOT_FINISHED if m.host.flash_busy() else codes.RC_OK)


def _delete_curves(m, arg, sub, data):
    m.host.curves.delete_all()
    return codes.RC_OK


def _add_curve(m, arg, sub, data):
    value = int.from_bytes(data, "little")
    return m.host.curves.add(arg, value & 0xFFFF, value >> 16)


def _add_curve_info16(m, arg, sub, data):
    return m.host.curves.add_info(arg, data[2:4])


def _add_curve_info32(m, arg, sub, data):
    return m.host.curves.add_info(arg, data)


def _add_curve_data16(m, arg, sub, data):
    return m.host.curves.add_data(arg, data[2:4])


def _add_curve_data32(m, arg, sub, data):
    return m.host.curves.add_data(arg, data)


def _get_curve(m, arg, sub):
    rc, info_size, data_size = m.host.curves.get(arg)
    return struct.pack("<BBH", rc, info_size, data_size)


def _read_curve_block(m, arg, sub):
    h = m.host
    block = "info" if sub == 0x61 else "data"
    return read_step(h.protocol.curve_read, lambda n: h.curves.read(arg, block, n))


def _log_counter(m, arg, sub):
    log = m.host.errlog
    return _words(len(log.entries), log.occurred)


def _log_entry(m, arg, sub):
    e = m.host.errlog.entry(arg)
    if e is None:
        raise SdoAbort(codes.ABORT_NO_DATA, f"error log entry {arg} is empty")
    return _words(0, e.code) if sub == 0x71 else _le(e.time_ms if sub == 0x72 else e.time_h)


def _error_text(m, arg, sub):
    text = m.host.profile.error_texts.get(arg, "")
    return _le(stringlets_of(text, 8)[sub - 0x74])


def _ct_delete_all(m, arg, sub, data):
    m.host.ct.delete_all()
    return codes.RC_OK


def _ct_delete(m, arg, sub, data):
    m.host.ct.delete(arg)
    return codes.RC_OK


def _ct_prepare(m, arg, sub, data):
    h = m.host
    value = int.from_bytes(data, "little")
    return h.ct.prepare(arg, value & 0xFFFF if h.protocol.ct_prepare_size_at == 4 else value >> 16)


def _ct_write(m, arg, sub, data):
    layout = m.host.protocol.ct_write
    return m.host.ct.write(arg, data[2:4] if layout == "data16_at6" else data[0:2] if layout == "data16_at4"
                           else data)


def _ct_get(m, arg, sub):
    h = m.host
    rc, size = h.ct.get(arg)
    layout = h.protocol.ct_get
    if layout == "rc4_size6":
        return struct.pack("<BBH", rc, 0, size)
    if layout == "size16_rc6":
        return struct.pack("<HBB", size, rc, 0)
    if rc != codes.RC_OK:          # size32: no result byte, so an absent entry has no data
        raise SdoAbort(codes.ABORT_NO_DATA, f"CT entry {arg} is not present")
    return _le(size)


def _ct_read(m, arg, sub):
    h = m.host
    return read_step(h.protocol.ct_read, lambda n: h.ct.read(arg, n))


def _ct_presence(m, arg, sub):
    return _le(m.host.ct.presence(sub - 0x87))


Read = Callable[["ManufacturerObjects", int, int], bytes]
Write = Callable[["ManufacturerObjects", int, int, bytes], "int | Reply"]


@dataclass(frozen=True)
class Service:
    """One manufacturer service: sub-index, scope (upid | system | curve | log | text | ct: which indexes have
    it), its handlers (read: upload, write: download; None: that direction is refused), the EDS data type.
    `flash_guard`: a write is refused while a flash save runs (the curve and command-table stores live in
    flash-backed RAM)."""
    sub: int
    name: str
    scope: str
    read: Read | None = None
    write: Write | None = None
    data_type: int = UNSIGNED32
    flash_guard: bool = False

    @property
    def access(self) -> str:
        return "rw" if self.read and self.write else "ro" if self.read else "wo"


def _rw(sub, name, scope, read=None, write=None, data_type=UNSIGNED32, flash_guard=False) -> Service:
    return Service(sub, name, scope, read, write, data_type, flash_guard)


# The E1100's services (spec 2.2, [CO1100]); the sub-index table is the manual's
E1100_SERVICES: tuple[Service, ...] = (
    _rw(0x01, "RAM value", "upid", _read_upid, _write_upid, INTEGER32),
    _rw(0x02, "ROM value", "upid", _read_upid, _write_upid, INTEGER32),
    _rw(0x03, "Min value", "upid", _read_upid, None, INTEGER32),
    _rw(0x04, "Max value", "upid", _read_upid, None, INTEGER32),
    _rw(0x05, "Default value", "upid", _read_upid, None, INTEGER32),
    _rw(0x06, "RAM and ROM write", "upid", None, _write_upid, INTEGER32),
    _rw(0x07, "Set ROM to default (OS)", "system", write=_set_layer_default),
    _rw(0x08, "Set ROM to default (MC SW)", "system", write=_set_layer_default),
    _rw(0x09, "Set ROM to default (Interface)", "system", write=_set_layer_default),
    _rw(0x0A, "Set ROM to default (Application)", "system", write=_set_layer_default),
    _rw(0x0B, "Reset drive", "system", write=_reset_drive),
    _rw(0x20, "Start getting UPID list", "system", write=_start_list),
    _rw(0x21, "Get next UPID list item", "system", read=_next_list_item),
    _rw(0x22, "Start getting modified UPID list", "system", write=_start_list),
    _rw(0x23, "Get next modified UPID list item", "system", read=_next_list_item),
    _rw(0x35, "Stop MC and application SW", "system", write=_stop_mc),
    _rw(0x36, "Start MC and application SW", "system", write=_start_mc),
    _rw(0x40, "Save curves RAM to flash", "system", write=_save_curves, flash_guard=True),
    _rw(0x41, "Delete all curves (RAM)", "system", write=_delete_curves, flash_guard=True),
    _rw(0x42, "Poll flash", "system", read=_poll_flash),
    _rw(0x50, "Add curve", "curve", write=_add_curve, flash_guard=True),
    _rw(0x51, "Add curve info block, 16 bit", "curve", write=_add_curve_info16, flash_guard=True),
    _rw(0x52, "Add curve data, 16 bit", "curve", write=_add_curve_data16, flash_guard=True),
    _rw(0x53, "Add curve data, 32 bit", "curve", write=_add_curve_data32, flash_guard=True),
    _rw(0x54, "Add curve info block, 32 bit", "curve", write=_add_curve_info32, flash_guard=True),
    _rw(0x60, "Get curve", "curve", read=_get_curve),
    _rw(0x61, "Get curve info block", "curve", read=_read_curve_block),
    _rw(0x62, "Get curve data", "curve", read=_read_curve_block),
    _rw(0x70, "Get error log entry counter", "system", read=_log_counter),
    _rw(0x71, "Get error log entry error code", "log", read=_log_entry),
    _rw(0x72, "Get error log entry time low", "log", read=_log_entry),
    _rw(0x73, "Get error log entry time high", "log", read=_log_entry),
    *[_rw(0x74 + n, f"Get error code text stringlet {n}", "text", read=_error_text) for n in range(8)],
    _rw(0x80, "CT save to flash (write) / poll flash (read)", "system", _poll_flash, _save_ct, flash_guard=True),
    _rw(0x81, "CT delete all entries (RAM)", "system", write=_ct_delete_all, flash_guard=True),
    _rw(0x82, "CT delete entry", "ct", write=_ct_delete, flash_guard=True),
    _rw(0x83, "CT write entry (prepare)", "ct", write=_ct_prepare, flash_guard=True),
    _rw(0x84, "CT write entry data, 16 bit", "ct", write=_ct_write, flash_guard=True),
    _rw(0x85, "CT get entry", "ct", read=_ct_get),
    _rw(0x86, "CT get entry data, 16 bit", "ct", read=_ct_read),
    *[_rw(0x87 + k, f"CT get entry list {32 * k}..{32 * k + 31}", "system", read=_ct_presence) for k in range(8)],
)


class ManufacturerObjects:
    """Dispatch of 2000h..5FFFh onto the drive (`host`) through its model's service table."""

    area = range(BASE, LAST + 1)        # the indexes the SDO server hands over (cia301/sdo.py)

    def __init__(self, host, services: Iterable[Service] = E1100_SERVICES):
        self.host = host
        self.services: Mapping[int, Service] = {s.sub: s for s in services}
        self.list_cursor: dict[bool, int | None] = {False: None, True: None}

    def reset(self) -> None:
        self.list_cursor = {False: None, True: None}

    # ---- object existence (also used by the EDS writer) ----
    def scope_applies(self, scope: str, arg: int) -> bool:
        if scope == "upid":
            return arg in self.host.params
        if scope == "system":
            return arg == 0
        if scope == "curve":
            return arg in CURVE_IDS
        if scope == "log":
            return arg in LOG_ENTRIES
        if scope == "ct":
            return (0 if self.host.protocol.ct_entry_zero else 1) <= arg <= 0xFF
        return 0 <= arg <= 0xFF     # text: error codes 00h..FFh

    def subs_at(self, index: int) -> list[Service]:
        arg = index - BASE
        return [s for s in self.services.values() if self.scope_applies(s.scope, arg)]

    def service(self, index: int, sub: int) -> Service | None:
        """The service at (index, sub); None for sub 0; SdoAbort when there is none."""
        if not BASE <= index <= LAST:
            raise SdoAbort(codes.ABORT_NO_OBJECT)
        arg = index - BASE
        s = self.services.get(sub)
        if s is not None and self.scope_applies(s.scope, arg):
            return s
        if not self.subs_at(index):
            raise SdoAbort(codes.ABORT_NO_OBJECT)
        if sub == 0:
            return None
        raise SdoAbort(codes.ABORT_NO_SUBINDEX)

    def upload(self, index: int, sub: int) -> bytes:
        s = self.service(index, sub)
        if s is None:   # sub 0: highest sub-index at this index
            return bytes([max(x.sub for x in self.subs_at(index))])
        if s.read is None:
            raise SdoAbort(codes.ABORT_WRITE_ONLY)
        return s.read(self, index - BASE, sub)

    def download(self, index: int, sub: int, data: bytes) -> int | Reply:
        s = self.service(index, sub)
        if s is None or s.write is None:
            raise SdoAbort(codes.ABORT_READ_ONLY)
        if s.flash_guard and self.host.flash_busy():
            raise SdoAbort(codes.ABORT_STATE, "flash save in progress")
        return s.write(self, index - BASE, sub, data)
