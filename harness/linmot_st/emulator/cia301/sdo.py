"""The drive's SDO server (CiA 301 protocol layer): expedited and segmented transfers for the standard objects,
expedited 4-byte transfers with the E1100 answer layout for the manufacturer objects 2000h..5FFFh.

`handle(data)` takes the 8 request bytes and returns the 8 response bytes, a `Pending` answer (sent later, with
an action at that moment), or None (no answer: an abort request from the client). It never raises on bad input: malformed
requests get an abort frame.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass

from .. import codes
from ..codes import SdoAbort

# command specifiers (byte 0, bits 7..5)
CCS_DOWNLOAD_SEGMENT, CCS_DOWNLOAD, CCS_UPLOAD, CCS_UPLOAD_SEGMENT, CCS_ABORT = 0, 1, 2, 3, 4
CCS_BLOCK_UPLOAD, CCS_BLOCK_DOWNLOAD = 5, 6


def abort_frame(index: int, sub: int, code: int) -> bytes:
    return struct.pack("<BHBI", 0x80, index & 0xFFFF, sub & 0xFF, code)


def download_response(index: int, sub: int, result: int = 0) -> bytes:
    """60h idx idx sub 00 00 RR 00: the E1100 puts its result code in byte 6 (spec 1)."""
    return struct.pack("<BHBBBBB", 0x60, index, sub, 0, 0, result, 0)


@dataclass
class Reply:
    """A manufacturer service's download answer that is not immediate: sent `delay_ns` after the request (plus
    the turnaround), `then` runs when it is sent (the end of the operation)."""
    code: int = codes.RC_OK
    delay_ns: int = 0
    then: Callable[[], None] | None = None


@dataclass
class Pending:
    """A response the drive sends `delay_ns` after the request's turnaround; `then` runs when it is sent."""
    response: bytes
    delay_ns: int
    then: Callable[[], None] | None


class SdoServer:
    def __init__(self, comm, manufacturer, nmt_pre_operational):
        self.comm = comm                    # CommObjects (1000h..1FFFh)
        self.mfr = manufacturer             # the manufacturer area: .area (its indexes), .upload, .download,
                                            # .service (linmot/manufacturer.py)
        self._mfr_area = manufacturer.area
        self._pre_op = nmt_pre_operational  # callable -> bool
        self._seg = None                    # segmented transfer in progress: [kind, index, sub, buffer, toggle]

    def reset(self) -> None:
        self._seg = None

    def handle(self, data: bytes) -> bytes | Pending | None:
        if len(data) < 8:
            # CiA 301 SDO frames always carry 8 bytes; a short one cannot be a valid request
            padded = data.ljust(4, b"\0")
            return abort_frame(padded[1] | padded[2] << 8, padded[3], codes.ABORT_GENERAL)
        cs = data[0]
        ccs = cs >> 5
        index = data[1] | data[2] << 8
        sub = data[3]
        if ccs in (CCS_UPLOAD_SEGMENT, CCS_DOWNLOAD_SEGMENT) and self._seg is not None:
            index, sub = self._seg[1], self._seg[2]     # a segment carries no index: abort names the transfer's
        try:
            if ccs == CCS_UPLOAD:
                self._seg = None
                return self._upload(index, sub)
            if ccs == CCS_DOWNLOAD:
                self._seg = None
                return self._download(cs, index, sub, data)
            if ccs == CCS_UPLOAD_SEGMENT:
                return self._upload_segment(cs)
            if ccs == CCS_DOWNLOAD_SEGMENT:
                return self._download_segment(cs, data)
            if ccs == CCS_ABORT:
                self._seg = None
                return None
            raise SdoAbort(codes.ABORT_COMMAND)   # block transfers (5, 6) and 7 are not supported
        except SdoAbort as exc:
            if ccs in (CCS_UPLOAD_SEGMENT, CCS_DOWNLOAD_SEGMENT):
                self._seg = None
            return abort_frame(index, sub, exc.code)

    # ---- upload ----
    def _upload(self, index: int, sub: int) -> bytes:
        if index in self._mfr_area:
            payload = self.mfr.upload(index, sub)
            if len(payload) == 1:                       # sub 0 "number of entries", UNSIGNED8
                return struct.pack("<BHB", 0x4F, index, sub) + payload + b"\0\0\0"
            return struct.pack("<BHB", 0x43, index, sub) + payload
        payload = self.comm.read(index, sub)
        n = len(payload)
        if 0 < n <= 4:
            return struct.pack("<BHB", 0x43 | (4 - n) << 2, index, sub) + payload.ljust(4, b"\0")
        self._seg = ["up", index, sub, bytearray(payload), 0]
        return struct.pack("<BHBI", 0x41, index, sub, n)

    def _upload_segment(self, cs: int) -> bytes:
        seg = self._seg
        if seg is None or seg[0] != "up":
            raise SdoAbort(codes.ABORT_COMMAND, "upload segment without an upload in progress")
        toggle = cs & 0x10
        if toggle != seg[4]:
            raise SdoAbort(codes.ABORT_TOGGLE)
        chunk, seg[3] = bytes(seg[3][:7]), seg[3][7:]
        last = not seg[3]
        seg[4] ^= 0x10
        if last:
            self._seg = None
        return bytes([toggle | (7 - len(chunk)) << 1 | int(last)]) + chunk.ljust(7, b"\0")

    # ---- download ----
    def _download(self, cs: int, index: int, sub: int, data: bytes):
        expedited, sized = cs & 0x02, cs & 0x01
        if index in self._mfr_area:
            if not expedited:
                # spec 1: every E1100 configuration service is expedited with 4 bytes
                self.mfr.service(index, sub)            # unknown object/sub first
                raise SdoAbort(codes.ABORT_UNSUPPORTED, "manufacturer objects take expedited transfers only")
            if sized and (cs >> 2) & 3:
                self.mfr.service(index, sub)
                raise SdoAbort(codes.ABORT_LENGTH, "manufacturer objects take exactly 4 bytes")
            result = self.mfr.download(index, sub, data[4:8])
            if isinstance(result, Reply):
                return Pending(download_response(index, sub, result.code), result.delay_ns, result.then)
            return download_response(index, sub, result)
        pre_op = self._pre_op()
        if expedited:
            n = 4 - ((cs >> 2) & 3) if sized else 4
            self.comm.write(index, sub, data[4:4 + n], pre_op)
            return download_response(index, sub)
        self.comm.check_write(index, sub, pre_op)
        size = struct.unpack_from("<I", data, 4)[0] if sized else None
        self._seg = ["down", index, sub, bytearray(), 0, size]
        return download_response(index, sub)

    def _download_segment(self, cs: int, data: bytes) -> bytes:
        seg = self._seg
        if seg is None or seg[0] != "down":
            raise SdoAbort(codes.ABORT_COMMAND, "download segment without a download in progress")
        toggle = cs & 0x10
        if toggle != seg[4]:
            raise SdoAbort(codes.ABORT_TOGGLE)
        seg[3] += data[1:8 - ((cs >> 1) & 7)]
        seg[4] ^= 0x10
        if cs & 0x01:                                   # last segment
            _, index, sub, buf, _, size = seg
            self._seg = None
            if size is not None and size != len(buf):
                raise SdoAbort(codes.ABORT_LENGTH)
            self.comm.write(index, sub, bytes(buf), self._pre_op())
        return bytes([0x20 | toggle]) + bytes(7)
