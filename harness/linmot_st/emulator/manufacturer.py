"""The E1100 manufacturer objects 2000h..5FFFh: the sub-index selects the service, the index carries its
argument (2000h + UPID / curve ID / CT entry / error-log entry / error code), spec 2.2.

Every transfer is expedited with 4 data bytes. A download answers 60h with the E1100 result code in byte 6
(`int` returned by a handler, or a `Reply` for services whose answer comes later); an upload answers 43h with
4 bytes. Requests the drive refuses raise `SdoAbort` (docs/emulator.md lists each choice).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Callable

from . import codes
from .codes import NoMoreData, NotStarted, SdoAbort
from .paramtypes import stringlets_of
from .params import NoValueAccess, NotWritable, OutOfRange, UnknownUpid

BASE = 0x2000
LAST = 0x5FFF
INTEGER32, UNSIGNED8, UNSIGNED32 = 4, 5, 7
LIST_END = 0xFFFF


@dataclass(frozen=True)
class Service:
    sub: int
    name: str
    scope: str          # upid | system | curve | log | text | ct
    access: str         # ro | wo | rw
    data_type: int = UNSIGNED32


SERVICES: dict[int, Service] = {s.sub: s for s in [
    Service(0x01, "RAM value", "upid", "rw", INTEGER32),
    Service(0x02, "ROM value", "upid", "rw", INTEGER32),
    Service(0x03, "Min value", "upid", "ro", INTEGER32),
    Service(0x04, "Max value", "upid", "ro", INTEGER32),
    Service(0x05, "Default value", "upid", "ro", INTEGER32),
    Service(0x06, "RAM and ROM write", "upid", "wo", INTEGER32),
    Service(0x07, "Set ROM to default (OS)", "system", "wo"),
    Service(0x08, "Set ROM to default (MC SW)", "system", "wo"),
    Service(0x09, "Set ROM to default (Interface)", "system", "wo"),
    Service(0x0A, "Set ROM to default (Application)", "system", "wo"),
    Service(0x0B, "Reset drive", "system", "wo"),
    Service(0x20, "Start getting UPID list", "system", "wo"),
    Service(0x21, "Get next UPID list item", "system", "ro"),
    Service(0x22, "Start getting modified UPID list", "system", "wo"),
    Service(0x23, "Get next modified UPID list item", "system", "ro"),
    Service(0x35, "Stop MC and application SW", "system", "wo"),
    Service(0x36, "Start MC and application SW", "system", "wo"),
    Service(0x40, "Save curves RAM to flash", "system", "wo"),
    Service(0x41, "Delete all curves (RAM)", "system", "wo"),
    Service(0x42, "Poll flash", "system", "ro"),
    Service(0x50, "Add curve", "curve", "wo"),
    Service(0x51, "Add curve info block, 16 bit", "curve", "wo"),
    Service(0x52, "Add curve data, 16 bit", "curve", "wo"),
    Service(0x53, "Add curve data, 32 bit", "curve", "wo"),
    Service(0x54, "Add curve info block, 32 bit", "curve", "wo"),
    Service(0x60, "Get curve", "curve", "ro"),
    Service(0x61, "Get curve info block", "curve", "ro"),
    Service(0x62, "Get curve data", "curve", "ro"),
    Service(0x70, "Get error log entry counter", "system", "ro"),
    Service(0x71, "Get error log entry error code", "log", "ro"),
    Service(0x72, "Get error log entry time low", "log", "ro"),
    Service(0x73, "Get error log entry time high", "log", "ro"),
    *[Service(0x74 + n, f"Get error code text stringlet {n}", "text", "ro") for n in range(8)],
    Service(0x80, "CT save to flash (write) / poll flash (read)", "system", "rw"),
    Service(0x81, "CT delete all entries (RAM)", "system", "wo"),
    Service(0x82, "CT delete entry", "ct", "wo"),
    Service(0x83, "CT write entry (prepare)", "ct", "wo"),
    Service(0x84, "CT write entry data, 16 bit", "ct", "wo"),
    Service(0x85, "CT get entry", "ct", "ro"),
    Service(0x86, "CT get entry data, 16 bit", "ct", "ro"),
    *[Service(0x87 + k, f"CT get entry list {32 * k}..{32 * k + 31}", "system", "ro") for k in range(8)],
]}

CURVE_IDS = range(1, 101)
LOG_ENTRIES = range(0, 21)        # LinUDP allows entry numbers 0..20 (spec 2.2)


@dataclass
class Reply:
    """A download answer that is not immediate: sent `delay_ns` after the request (plus the turnaround),
    `then` runs when it is sent (the end of the operation)."""
    code: int = codes.RC_OK
    delay_ns: int = 0
    then: Callable[[], None] | None = None


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


class ManufacturerObjects:
    """Dispatch of 2000h..5FFFh onto the drive (`host`: an E1100Drive)."""

    def __init__(self, host):
        self.host = host
        self._list_cursor: dict[bool, int | None] = {False: None, True: None}

    def reset(self) -> None:
        self._list_cursor = {False: None, True: None}

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
        return [s for s in SERVICES.values() if self.scope_applies(s.scope, arg)]

    def service(self, index: int, sub: int) -> Service | None:
        """The service at (index, sub); None for sub 0; SdoAbort when there is none."""
        if not BASE <= index <= LAST:
            raise SdoAbort(codes.ABORT_NO_OBJECT)
        arg = index - BASE
        s = SERVICES.get(sub)
        if s is not None and self.scope_applies(s.scope, arg):
            return s
        if not self.subs_at(index):
            raise SdoAbort(codes.ABORT_NO_OBJECT)
        if sub == 0:
            return None
        raise SdoAbort(codes.ABORT_NO_SUBINDEX)

    # ---- upload (read) ----
    def upload(self, index: int, sub: int) -> bytes:
        s = self.service(index, sub)
        arg = index - BASE
        if s is None:   # sub 0: highest sub-index at this index
            return bytes([max(x.sub for x in self.subs_at(index))])
        if s.access == "wo":
            raise SdoAbort(codes.ABORT_WRITE_ONLY)
        h = self.host
        if s.scope == "upid":
            what = {1: "ram", 2: "rom", 3: "min", 4: "max", 5: "default"}[sub]
            try:
                return _le(h.params.read(arg, what))
            except NoValueAccess as exc:
                raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None
        if sub in (0x21, 0x23):
            return self._next_list_item(modified=sub == 0x23)
        if sub in (0x42, 0x80):
            return _le(codes.RC_NOT_FINISHED if h.flash_busy() else codes.RC_OK)
        if sub == 0x60:
            rc, info_size, data_size = h.curves.get(arg)
            return struct.pack("<BBH", rc, info_size, data_size)
        if sub in (0x61, 0x62):
            block = "info" if sub == 0x61 else "data"
            return read_step(h.protocol.curve_read, lambda n: h.curves.read(arg, block, n))
        if sub == 0x70:
            return _words(len(h.errlog.entries), h.errlog.occurred)
        if sub in (0x71, 0x72, 0x73):
            e = h.errlog.entry(arg)
            if e is None:
                raise SdoAbort(codes.ABORT_NO_DATA, f"error log entry {arg} is empty")
            return _words(0, e.code) if sub == 0x71 else _le(e.time_ms if sub == 0x72 else e.time_h)
        if 0x74 <= sub <= 0x7B:
            text = h.profile.error_texts.get(arg, "")
            return _le(stringlets_of(text, 8)[sub - 0x74])
        if sub == 0x85:
            rc, size = h.ct.get(arg)
            layout = h.protocol.ct_get
            if layout == "rc4_size6":
                return struct.pack("<BBH", rc, 0, size)
            if layout == "size16_rc6":
                return struct.pack("<HBB", size, rc, 0)
            if rc != codes.RC_OK:          # size32: no result byte, so an absent entry has no data
                raise SdoAbort(codes.ABORT_NO_DATA, f"CT entry {arg} is not present")
            return _le(size)
        if sub == 0x86:
            return read_step(h.protocol.ct_read, lambda n: h.ct.read(arg, n))
        if 0x87 <= sub <= 0x8E:
            return _le(h.ct.presence(sub - 0x87))
        raise AssertionError(f"no upload handler for sub {sub:02X}h")  # pragma: no cover

    def _next_list_item(self, modified: bool) -> bytes:
        cursor = self._list_cursor[modified]
        if cursor is None:
            raise SdoAbort(codes.ABORT_STATE, "get next UPID without start (20h/22h)")
        p = self.host.params.next_entry(cursor, modified_only=modified)
        if p is None:
            self._list_cursor[modified] = LIST_END + 1
            return _words(0, LIST_END)
        self._list_cursor[modified] = p.upid + 1
        return _words(p.address_usage, p.upid)

    # ---- download (write) ----
    def download(self, index: int, sub: int, data: bytes) -> int | Reply:
        s = self.service(index, sub)
        if s is None or s.access == "ro":
            raise SdoAbort(codes.ABORT_READ_ONLY)
        arg = index - BASE
        value = int.from_bytes(data, "little")
        lo, hi = value & 0xFFFF, value >> 16
        h = self.host
        if s.scope == "upid":
            ram, rom = {1: (True, False), 2: (False, True), 6: (True, True)}[sub]
            try:
                h.params.write(arg, value, ram=ram, rom=rom)
            except UnknownUpid as exc:   # pragma: no cover - excluded by service()
                raise SdoAbort(codes.ABORT_NO_OBJECT, str(exc)) from None
            except NoValueAccess as exc:
                raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None
            except NotWritable as exc:
                raise SdoAbort(codes.ABORT_READ_ONLY, str(exc)) from None
            except OutOfRange as exc:
                raise SdoAbort(codes.ABORT_RANGE, str(exc)) from None
            return codes.RC_OK
        if 0x07 <= sub <= 0x0A:
            return h.set_layer_default(sub - 0x06)
        if sub == 0x0B:
            return Reply(then=h.software_reset)
        if sub in (0x20, 0x22):
            self._list_cursor[sub == 0x22] = hi
            return h.protocol.list_start_result   # 04h: the [CO1100] example (its table says 00h: DOC-ERR)
        if sub == 0x35:
            return h.stop_mc()
        if sub == 0x36:
            return h.start_mc()
        # the curve and command-table stores live in flash-backed RAM: no changes while the flash is written
        if h.flash_busy():
            raise SdoAbort(codes.ABORT_STATE, "flash save in progress")
        if sub in (0x40, 0x80):
            return h.save_to_flash("curves" if sub == 0x40 else "ct")
        if sub == 0x41:
            h.curves.delete_all()
            return codes.RC_OK
        if sub == 0x50:
            return h.curves.add(arg, lo, hi)
        if sub == 0x51:
            return h.curves.add_info(arg, data[2:4])
        if sub == 0x54:
            return h.curves.add_info(arg, data)
        if sub == 0x52:
            return h.curves.add_data(arg, data[2:4])
        if sub == 0x53:
            return h.curves.add_data(arg, data)
        if sub == 0x81:
            h.ct.delete_all()
            return codes.RC_OK
        if sub == 0x82:
            h.ct.delete(arg)
            return codes.RC_OK
        if sub == 0x83:
            return h.ct.prepare(arg, lo if h.protocol.ct_prepare_size_at == 4 else hi)
        if sub == 0x84:
            layout = h.protocol.ct_write
            return h.ct.write(arg, data[2:4] if layout == "data16_at6" else data[0:2] if layout == "data16_at4"
                              else data)
        raise AssertionError(f"no download handler for sub {sub:02X}h")  # pragma: no cover
