"""Process data of the E1100 ([CO1100] sections 4-5, spec/linmot-canopen.md 4, spec/linmot-motion.md 4): what
the RxPDOs feed into the MC (control word, motion command interface), what the TxPDOs carry, and when they go.

Mapping. The E1100 maps its PDOs with LinMot interface parameters, not with CiA 301 mapping objects. The
defaults are the manual's; the mapping parameters (UPIDs 2030h..2042h, INVENTED) select the other contents the
manual names: RxPDO1 "Control Word + Motion Cmd Header + Par Byte 0..3", RxPDO3 "CMD Slave Header + Par Byte
6..7 / 6..9 / 6..11" or "Direct Par 1, 2", TxPDO1/TxPDO2 default or "By UPID", TxPDO3 "By UPID" (up to four words;
a 32-bit UPID takes two). The mapping is read when the node enters Operational (INFERRED: as CiA 301 devices
fix theirs); a bad one logs the interface error code (D1h..DCh) and that PDO stays off.

Motion command consistency: a command executes when its header carries a new count and, where RxPDO3 carries
the slave header, the slave header's low 4 bits equal that count ([CO1100] p.18). With RxPDO3 off (COB-ID
bit 31) or mapped to Direct Par, the header alone triggers (INFERRED).

Transmission. TxPDO type 254/255: on change, checked after every event and MC cycle, at most once per inhibit
time (1800h+n sub 3, 100 us), and at least once per event timer (sub 5, ms) where set; 1..240: every n-th SYNC;
250 (LinMot): TxPDO n right after RxPDO n. RxPDOs are evaluated on arrival, or on the next SYNC where any TxPDO
is synchronous, an RxPDO's own type is 1, or parameter 2042h asks for it. PDOs flow only in Operational.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from ...protocol.upids import V_LOGGED_ERROR, V_STATE_VAR, V_STATUS_WORD, V_WARN_WORD

# mapping parameters (interface layer; UPIDs INVENTED)
P_TX_MODE = (0x2030, 0x2035, None)              # 0 = default content, 1 = by UPID (TxPDO3: always by UPID)
P_TX_UPIDS = ((0x2031, 0x2032, 0x2033, 0x2034), (0x2036, 0x2037, 0x2038, 0x2039), (0x203B, 0x203C, 0x203D, 0x203E))
P_RX1_MODE = 0x2040                             # 0 = control word, 1 = control word + header + par bytes 0..3
P_RX3_MODE = 0x2041                             # 0/1/2 = slave header + par bytes 6..7 / 6..9 / 6..11, 3 = direct par
P_RX_ON_SYNC = 0x2042                           # evaluate RxPDOs on SYNC with all TxPDOs asynchronous
P_DIRECT_PAR_UPIDS = (0x2050, 0x2051)

# interface error codes ([CO1100] 8, spec 4.5)
ERR_INVALID_TX_MAPPING = 0xD1                   # + n
ERR_INVALID_TX_UPID = 0xD7                      # + n

RX3_LENGTH = {0: 4, 1: 6, 2: 8, 3: 4}
# the MC words that change only at events, never within quiet cycles (status word, state var, logged error, warn)
EVENT_WORDS = frozenset({V_STATUS_WORD, V_STATE_VAR, V_LOGGED_ERROR, V_WARN_WORD})


class _Tx:
    __slots__ = ("n", "cob", "ttype", "inhibit_ns", "event_ns", "pack", "last", "last_sent", "due", "event_due",
                 "sync_count", "cycle_sensitive")

    def __init__(self, n: int):
        self.n = n
        self.cob = None
        self.ttype = 254
        self.inhibit_ns = self.event_ns = 0
        self.pack: Callable[[], bytes] | None = None
        self.last: bytes | None = None
        self.last_sent: int | None = None
        self.due: int | None = None           # deferred by the inhibit time
        self.event_due: int | None = None
        self.sync_count = 0
        self.cycle_sensitive = True           # its content may change in any MC cycle (positions...)


class ProcessData:
    def __init__(self, drive):
        self.drive = drive
        self.tx = [_Tx(n) for n in range(3)]
        self.rx_cob: list[int | None] = [None, None, None]
        self.rx1_mode = self.rx3_mode = 0
        self.rx_on_sync = self.slave_used = self.cycle_sensitive = False
        self.sync_cob = 0x080
        self.rx_ids: frozenset[int] = frozenset()
        self.operational = False
        self._sync_tx: list[_Tx] = []
        self._event_tx: list[_Tx] = []
        self._timed_tx: list[_Tx] = []
        self._sensitive_tx: list[_Tx] = []
        self.reset_image()

    # ------------------------------------------------------------------ configuration
    def reset_image(self) -> None:
        """Power-on / boot: the motion command interface holds zeros."""
        self.header = 0
        self.params = bytearray(32)
        self.slave = 0
        self._rx_pending: list[bytes | None] = [None, None, None]

    def start(self, t: int) -> None:
        """The node enters Operational: read the communication and mapping parameters, publish."""
        d = self.drive
        comm, params = d.comm, d.mc.params
        self.rx1_mode = params[P_RX1_MODE].ram if P_RX1_MODE in params else 0
        self.rx3_mode = params[P_RX3_MODE].ram if P_RX3_MODE in params else 0
        sync_rx = bool(params[P_RX_ON_SYNC].ram) if P_RX_ON_SYNC in params else False
        for n in range(3):
            cob = comm.value(0x1400 + n, 1)
            self.rx_cob[n] = None if cob & 0x80000000 else cob & 0x7FF
            sync_rx = sync_rx or comm.value(0x1400 + n, 2) == 1
        for tx in self.tx:
            n = tx.n
            cob = comm.value(0x1800 + n, 1)
            tx.cob = None if cob & 0x80000000 else cob & 0x7FF
            tx.ttype = comm.value(0x1800 + n, 2)
            tx.inhibit_ns = comm.value(0x1800 + n, 3) * 100_000
            tx.event_ns = comm.value(0x1800 + n, 5) * 1_000_000
            tx.last = tx.last_sent = tx.due = tx.event_due = None
            tx.sync_count = 0
            tx.pack, tx.cycle_sensitive = self._mapping(n, t)
            sync_rx = sync_rx or 1 <= tx.ttype <= 240
        self.rx_on_sync = sync_rx
        # the TxPDOs each SYNC and each publish() look at (fixed until the next start)
        self._sync_tx = [tx for tx in self.tx if 1 <= tx.ttype <= 240]
        self._event_tx = [tx for tx in self.tx if tx.ttype >= 254 and tx.pack is not None and tx.cob is not None]
        # only these ever get a timer: `due` needs an inhibit time, `event_due` an event timer
        self._timed_tx = [tx for tx in self.tx if tx.inhibit_ns or tx.event_ns]
        # the event-driven TxPDOs whose content may change in a quiet MC cycle (positions...)
        self._sensitive_tx = [tx for tx in self._event_tx if tx.cycle_sensitive]
        self.slave_used = self.rx_cob[2] is not None and self.rx3_mode in (0, 1, 2)
        self.sync_cob = comm.value(0x1005) & 0x7FF
        # what the drive accepts while Operational: NMT, its SDO requests and what handles() takes (its
        # acceptance filter on the simulated bus, E1100Drive.rx_filter)
        self.rx_ids = frozenset([0x000, 0x600 + d.node_id, self.sync_cob, *(c for c in self.rx_cob if c is not None)])
        self._rx_pending = [None, None, None]
        self.operational = True
        self._update_sensitivity()
        self.publish(t)

    def stop(self) -> None:
        self.operational = False
        self.cycle_sensitive = False

    def _mapping(self, n: int, t: int) -> tuple[Callable[[], bytes] | None, bool]:
        """The packer of TxPDO n, and whether its content can change in a quiet MC cycle (positions...)."""
        params = self.drive.mc.params
        mode_upid = P_TX_MODE[n]
        by_upid = mode_upid is None or (mode_upid in params and params[mode_upid].ram == 1)
        if not by_upid:
            return self._default_packer(n), n != 0      # TxPDO1's words change only at events
        else:
            items, upids = [], []
            for upid_par in P_TX_UPIDS[n]:
                upid = params[upid_par].ram if upid_par in params else 0
                if upid == 0:
                    continue
                if upid not in params or params[upid].d.kind == "string":
                    self.drive.interface_error(ERR_INVALID_TX_UPID + n, t)
                    return None, False
                items.append(self._upid_item(upid))
                upids.append(upid)
        fmt = "<" + "".join(code for code, _ in items)
        if struct.calcsize(fmt) > 8:
            self.drive.interface_error(ERR_INVALID_TX_MAPPING + n, t)
            return None, False
        if not items:
            return None, False
        getters = [g for _, g in items]
        sensitive = not set(upids) <= EVENT_WORDS
        return (lambda: struct.pack(fmt, *(g() for g in getters))), sensitive

    def _default_packer(self, n: int) -> Callable[[], bytes] | None:
        """The manual's default contents ([CO1100] 5.1), packed straight from the MC's outputs (per cycle)."""
        mc = self.drive.mc
        pack = struct.Struct("<HHHH").pack
        if n == 0:                      # status word, state var, logged error code, warn word
            # publish() packs it after every SYNC and MC cycle to compare, but mc.words is a new tuple only
            # when an event or cycle recorded the words: the same tuple packs to the same bytes
            memo: list = [None, b""]

            def words() -> bytes:
                w = mc.words
                if w is not memo[0]:
                    memo[0], memo[1] = w, pack(*w)
                return memo[1]
            return words
        if n == 1:                      # motion command status, actual position 16 bit, current, demand pos 16 bit
            return mc.txpdo2_payload
        return None                     # TxPDO3: empty unless mapped by UPID

    def _upid_item(self, upid: int) -> tuple[str, Callable[[], int]]:
        p = self.drive.mc.params[upid]
        mc = self.drive.mc
        bits, signed = p.d.type.bits, p.d.type.signed
        code = ("i" if signed else "I") if bits > 16 else ("h" if signed else "H")

        def get() -> int:
            v = mc.variable(upid)
            return p.ram if v is None else v
        return code, get

    def _update_sensitivity(self) -> None:
        """cycle_sensitive: an event-driven TxPDO's content may change in any MC cycle, so the MC must run
        cycle by cycle (and may not compute ahead). Not while each such TxPDO waits for its inhibit time to end
        (`due`): a change in a cycle before then sends nothing (publish skips it), and at `due` the TxPDO goes
        with the content of that time, so the quiet cycles up to it may be computed ahead (issue 24: with the
        bus budget's inhibit time, 16 axes at 500 kbit/s, about 10 cycles per wake instead of one)."""
        self.cycle_sensitive = self.operational and any(tx.due is None for tx in self._sensitive_tx)

    def handles(self, cid: int) -> bool:
        return self.operational and (cid == self.sync_cob or cid in self.rx_cob)

    # ------------------------------------------------------------------ frames in
    def on_frame(self, cid: int, data: bytes, t: int) -> None:
        if cid == self.sync_cob:
            self._on_sync(t)
            return
        for n in range(3):
            if cid == self.rx_cob[n]:
                if self.rx_on_sync:
                    self._rx_pending[n] = data
                else:
                    self._apply_rx(n, data, t)
                    self.publish(t)
                    if self.tx[n].ttype == 250:
                        self._send(self.tx[n], t)
                return

    def _apply_rx(self, n: int, data: bytes, t: int) -> None:
        mc = self.drive.mc
        if n == 0:
            need = 8 if self.rx1_mode == 1 else 2
            if len(data) < need:
                return              # INFERRED: a PDO shorter than its mapping is not processed (CiA 301)
            mc.set_control_word(data[0] | data[1] << 8, t)
            if self.rx1_mode == 1:
                self.header = data[2] | data[3] << 8
                self.params[0:4] = data[4:8]
                self._command(t)
        elif n == 1:
            if len(data) < 8:
                return
            self.header = data[0] | data[1] << 8
            self.params[0:6] = data[2:8]
            self._command(t)
        else:
            mode = self.rx3_mode
            if len(data) < RX3_LENGTH.get(mode, 4):
                return
            if mode == 3:
                self._direct_pars(data)
                return
            self.slave = data[0] | data[1] << 8
            end = {0: 4, 1: 6, 2: 8}.get(mode, 4)
            self.params[6:6 + end - 2] = data[2:end]
            self._command(t)

    def _command(self, t: int) -> None:
        if self.slave_used and (self.slave & 0xF) != (self.header & 0xF):
            return
        self.drive.mc.command_image(self.header, bytes(self.params), t)

    def _direct_pars(self, data: bytes) -> None:
        """RxPDO3 as Direct Par 1 / 2: 16-bit values for the live parameters named by 2050h / 2051h."""
        params = self.drive.mc.params
        for k, upid_par in enumerate(P_DIRECT_PAR_UPIDS):
            upid = params[upid_par].ram if upid_par in params else 0
            if upid and upid in params:
                self.drive.mc._write_live(upid, data[2 * k] | data[2 * k + 1] << 8)

    def _on_sync(self, t: int) -> None:
        pending = self._rx_pending
        if self.rx_on_sync and (pending[0] is not None or pending[1] is not None or pending[2] is not None):
            for n in range(3):
                data, pending[n] = pending[n], None
                if data is not None:
                    self._apply_rx(n, data, t)
        for tx in self._sync_tx:
            tx.sync_count += 1
            if tx.sync_count >= tx.ttype:
                tx.sync_count = 0
                self._send(tx, t)
        self.publish(t)

    # ------------------------------------------------------------------ frames out
    def publish(self, t: int) -> None:
        """Event-driven TxPDOs (254, 255) whose content changed go now, or when their inhibit time ends."""
        if not self.operational:
            return
        for tx in self._event_tx:
            if tx.last_sent is None:
                self._send(tx, t)               # entering Operational: every event-driven TxPDO goes once
                continue
            if tx.due is not None:
                continue
            payload = tx.pack()
            if payload == tx.last:
                continue
            earliest = tx.last_sent + tx.inhibit_ns
            if t >= earliest:
                self._send(tx, t, payload)
            else:
                tx.due = earliest
                if tx.cycle_sensitive:
                    self._update_sensitivity()

    def _send(self, tx: _Tx, t: int, payload: bytes | None = None) -> None:
        if tx.pack is None or tx.cob is None:
            return
        if payload is None:
            payload = tx.pack()
        deferred = tx.due is not None
        tx.last, tx.last_sent, tx.due = payload, t, None
        if deferred:
            self._update_sensitivity()
        if tx.event_ns and tx.ttype >= 254:
            tx.event_due = t + tx.event_ns
        self.drive.send_pdo(t, tx.cob, payload)

    def next_timer_ns(self) -> int | None:
        if not self.operational:
            return None
        best = None
        for tx in self._timed_tx:          # asked after every frame on the bus, by every drive
            due = tx.due
            if due is not None and (best is None or due < best):
                best = due
            due = tx.event_due
            if due is not None and (best is None or due < best):
                best = due
        return best

    def on_timer(self, t: int) -> None:
        if not self.operational:
            return
        for tx in self._timed_tx:
            if tx.due is not None and tx.due <= t:
                tx.due = None
                self._update_sensitivity()
                payload = tx.pack()
                if payload != tx.last:
                    self._send(tx, t, payload)
            if tx.event_due is not None and tx.event_due <= t:
                self._send(tx, t)
