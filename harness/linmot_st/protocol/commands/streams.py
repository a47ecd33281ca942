"""P, PV and PVA streams (seed 004 4.2 master ID 03h; [MC] 4.3.38..44, 5.4): the PLC sends one setpoint per
cycle, the drive stamps it with its receive time and replays the stream 1.5 periods late, interpolating finely
between setpoints (emulator/linmot/motion/stream.py). On CANopen only with synchronous PDOs, transmission type 1
([MC] 5.4 footnote): the drive then takes its RxPDOs on SYNC, so the stamps are the SYNC times.

Beside the rows: each command's period range and whether it takes the configured period (UPID 14E6h) instead
of the measured one for the derivatives ([MC] 4.3.40, 4.3.41, 4.3.43)."""

from __future__ import annotations

from .row import CommandDef, Field, Kind, register, seed_drives

P_STREAM = 0x030
PV_STREAM = 0x031
P_STREAM_CONFIGURED_PERIOD = 0x032
PV_STREAM_CONFIGURED_PERIOD = 0x033
PVA_STREAM = 0x034
PVA_STREAM_CONFIGURED_PERIOD = 0x035
STOP_STREAMING = 0x03F

_P = Field("position", "DINT", "0.1 um")
_V = Field("velocity", "DINT", "1 um/s")
_A = Field("acceleration", "DINT", "1E-5 m/s2")

# the nominal period the first two setpoints may set, ns: [MC] 4.3.38..40 and 5.4 say 2..5 ms for the P and
# PV streams, 4.3.41..43 0.4..10 ms for 033h..035h (031h: 2..5 ms by 4.3.39)
STREAM_PERIOD_RANGE_NS = {P_STREAM: (2_000_000, 5_000_000), PV_STREAM: (2_000_000, 5_000_000),
                   P_STREAM_CONFIGURED_PERIOD: (2_000_000, 5_000_000),
                   PV_STREAM_CONFIGURED_PERIOD: (400_000, 10_000_000),
                   PVA_STREAM: (400_000, 10_000_000), PVA_STREAM_CONFIGURED_PERIOD: (400_000, 10_000_000)}
# the derivatives use the configured period 14E6h, not the measured stamps
STREAM_CONFIGURED_PERIOD = frozenset({P_STREAM_CONFIGURED_PERIOD, PV_STREAM_CONFIGURED_PERIOD,
                               PVA_STREAM_CONFIGURED_PERIOD})


def _stream(cid, name, fields, mc):
    return CommandDef(cid, name, fields, Kind.STREAM, needs_homing=True, drives=seed_drives(cid),
                      source=f"[MC] 4.3.{mc}")


register(
    _stream(P_STREAM, "P Stream With Slave Generated Time Stamp", (_P,), 38),
    _stream(PV_STREAM, "PV Stream With Slave Generated Time Stamp", (_P, _V), 39),
    _stream(P_STREAM_CONFIGURED_PERIOD, "P Stream With Slave Generated Time Stamp and Configured Period Time",
            (_P,), 40),
    _stream(PV_STREAM_CONFIGURED_PERIOD, "PV Stream With Slave Generated Time Stamp and Configured Period Time",
            (_P, _V), 41),
    _stream(PVA_STREAM, "PVA Stream With Slave Generated Time Stamp", (_P, _V, _A), 42),
    _stream(PVA_STREAM_CONFIGURED_PERIOD,
            "PVA Stream With Slave Generated Time Stamp and Configured Period Time", (_P, _V, _A), 43),
    CommandDef(STOP_STREAMING, "Stop Streaming", (), Kind.STREAM_STOP, drives=seed_drives(STOP_STREAMING),
               source="[MC] 4.3.44"),
)
