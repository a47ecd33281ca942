"""CiA 301 NMT slave: the NMT states, the NMT commands, the boot-up message and the heartbeat producer
(1017h), as a mixin of the emulated drive (linmot/drive.py), which schedules (`_at`), sends (`_send`) and says
what a reset of the node does (`_start_boot`).

The drive keeps `nmt_state` as a plain attribute: on_frame reads it for every frame its filter lets in.
"""

from __future__ import annotations

MS = 1_000_000

# NMT states (heartbeat state byte in brackets)
OFF, BOOTING, PRE_OPERATIONAL, OPERATIONAL, STOPPED = "OFF", "BOOTING", "PRE-OPERATIONAL", "OPERATIONAL", "STOPPED"
_HEARTBEAT_STATE = {PRE_OPERATIONAL: 0x7F, OPERATIONAL: 0x05, STOPPED: 0x04}


class NmtSlave:
    """NMT and heartbeat of a CANopen node. The host class provides node_id, nmt_state, comm (1017h), pdo
    (start/stop), sdo (reset), timings.reset_communication_ns, now_ns, _comm_gen, _hb_gen, _sdo_busy, _at,
    _send and _start_boot (NMT Reset Node)."""

    def _enter_pre_operational(self, t: int) -> None:
        self.nmt_state = PRE_OPERATIONAL
        self.pdo.stop()
        self._send(t, 0x700 + self.node_id, b"\x00")        # boot-up message
        self._restart_heartbeat(t)

    def _nmt_command(self, data: bytes, t: int) -> None:
        if len(data) < 2 or data[1] not in (0, self.node_id):
            return
        cs = data[0]
        if cs == 0x01:
            if self.nmt_state != OPERATIONAL:
                self.nmt_state = OPERATIONAL
                self.pdo.start(t)
        elif cs == 0x02:
            self.nmt_state = STOPPED
            self.pdo.stop()
        elif cs == 0x80:
            self.nmt_state = PRE_OPERATIONAL
            self.pdo.stop()
        elif cs == 0x81:
            self._start_boot(t)
        elif cs == 0x82:
            self._comm_gen += 1
            self._sdo_busy = False
            self.nmt_state = BOOTING
            self.pdo.stop()
            self.sdo.reset()
            self.comm.reset()
            self._at(t + self.timings.reset_communication_ns, self._enter_pre_operational, comm=True)

    def _restart_heartbeat(self, t: int) -> None:
        self._hb_gen += 1
        period = self.comm.value(0x1017) * MS
        if period:
            gen = self._hb_gen
            self._at(t + period, lambda te: self._heartbeat(te, gen, period), comm=True)

    def _heartbeat(self, t: int, gen: int, period: int) -> None:
        if gen != self._hb_gen:
            return
        state = _HEARTBEAT_STATE.get(self.nmt_state)
        if state is not None:
            self._send(t, 0x700 + self.node_id, bytes([state]))
        self._at(t + period, lambda te: self._heartbeat(te, gen, period), comm=True)

    def _comm_changed(self, index: int, sub: int) -> None:
        """A write to a communication object: a new heartbeat producer time takes effect at once."""
        if index == 0x1017:
            self._restart_heartbeat(self.now_ns)
