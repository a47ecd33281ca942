"""ProtocolOptions: the answers the sources leave open, each with its alternatives (docs/emulator.md,
"Protocol options", gives the evidence for every default and ranks the weakest inferences).

The defaults are what the emulator answers and what the ST library implements. Another value makes the
emulator answer as a real drive might instead, so that a real drive's answers can be compared with the
library's expectation; it is not a mode the library supports.

Layout names say what bytes 4..7 of the SDO frame carry:
  data32      4 data bytes in bytes 4..7, no result code (a read after the end aborts 08000024h)
  rc4_data16  result code in byte 4, 2 data bytes in bytes 6..7 (the layout of 60h's answer)
  data16_rc6  2 data bytes in bytes 4..5, result code in byte 6 (where a 60h download answer has it)
"""

from __future__ import annotations

from dataclasses import dataclass

READ_LAYOUTS = ("data32", "rc4_data16", "data16_rc6")       # 61h/62h, 86h upload answers
WRITE_LAYOUTS = ("data16_at6", "data16_at4", "data32")      # 84h request: 2 bytes in 6..7 / 4..5, or 4 bytes
CT_GET_LAYOUTS = ("rc4_size6", "size16_rc6", "size32")      # 85h upload answer
SAVE_REFUSALS = ("result", "abort")                         # 40h/80h with the MC software running


@dataclass(frozen=True)
class ProtocolOptions:
    """Alternatives for each gap in the E1100 CANopen sources; the defaults are the emulator's choices."""
    curve_read: str = "data32"          # 61h/62h get info block / data: layout of each read step
    list_start_result: int = 0x04       # 20h/22h start (modified) UPID list: result in byte 6, 04h or 00h
    ct_prepare_size_at: int = 4         # 83h CT prepare: the block size in bytes 4..5 (4) or 6..7 (6)
    ct_write: str = "data16_at6"        # 84h CT write data: where the data of a step is, and how much
    ct_get: str = "rc4_size6"           # 85h CT get entry: layout of the answer
    ct_read: str = "rc4_data16"         # 86h CT get entry data: layout of each read step
    ct_entry_zero: bool = True          # CT entry 0 exists (entries 0..255) or not (1..255)
    save_refusal: str = "result"        # 40h/80h with the MC running: result D7h in byte 6, or abort 08000022h

    def __post_init__(self) -> None:
        for name, allowed in (("curve_read", READ_LAYOUTS), ("ct_read", READ_LAYOUTS), ("ct_write", WRITE_LAYOUTS),
                              ("ct_get", CT_GET_LAYOUTS), ("save_refusal", SAVE_REFUSALS),
                              ("list_start_result", (0x04, 0x00)), ("ct_prepare_size_at", (4, 6)),
                              ("ct_entry_zero", (True, False))):
            value = getattr(self, name)
            if value not in allowed or type(value) is not type(allowed[0]):
                raise ValueError(f"ProtocolOptions.{name} = {value!r}: expected one of "
                                 f"{', '.join(repr(a) for a in allowed)}")

    @property
    def ct_write_step(self) -> int:
        """Data bytes per 84h step."""
        return 4 if self.ct_write == "data32" else 2

    @property
    def ct_read_step(self) -> int:
        """Data bytes per 86h step."""
        return 4 if self.ct_read == "data32" else 2

    @property
    def curve_read_step(self) -> int:
        """Data bytes per 61h/62h step."""
        return 4 if self.curve_read == "data32" else 2
