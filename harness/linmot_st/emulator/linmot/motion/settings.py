"""MotionSettings: the choices of the motion model that no source fixes (docs/emulator.md, section 13).

Units: positions in the drive's 0.1 um ("pu"), times in ns, frequencies in Hz. Every default is INFERRED
unless its comment names a source; change them per drive: E1100Drive(1, motion=MotionSettings(...)).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

MS = 1_000_000
MM = 10_000          # pu per millimetre


@dataclass(frozen=True)
class MotionSettings:
    # MC cycle: setpoints are generated, the axis moves and the TxPDOs are checked for change once per cycle
    cycle_ns: int = 1 * MS

    # the axis: a position loop with velocity feedforward, a critically damped second-order follower of the
    # demand (following error ~ acceleration / (2 pi f)^2 while accelerating, none at constant velocity)
    bandwidth_hz: float = 25.0
    damping: float = 1.0
    acc_feedforward: float = 0.8        # 0..1: share of the demand acceleration fed forward
    settle_pu: float = 0.5              # |error| and |velocity| x 1 ms below this: the axis is at rest
    coast_decel_pu_s2: float = 50_000_000.0  # power stage off: friction and back-EMF slow the slider (5 m/s^2)

    # the mechanics in the slider's own frame (pu): mechanical stops, and where the slider is at power-on
    stop_negative_pu: int = 0
    stop_positive_pu: int = 300 * MM          # 300 mm stroke
    start_position_pu: int = 20 * MM          # 20 mm from the negative stop

    # in target position (status word bit 10): setpoint generation finished and |target - actual| <= window
    # for at least the hold time
    in_target_window_pu: int = 1000     # 0.1 mm
    in_target_hold_ns: int = 0

    # homing on a mechanical stop: the stop is found when the following error exceeds this
    homing_stop_error_pu: int = 5000    # 0.5 mm

    # motion commands (other than NOP, control word, live parameter, master homing and stops) need the axis
    # homed, else error 0080h ([MC] 10: "action that requires the motor to be already homed")
    motion_requires_homing: bool = True

    # a VAI stop (017xh, 027xh, 097xh, 0A7xh) also drops a queued "After Actual Command" move and an armed
    # position transition; False: only 008xh and leaving Operation Enabled do, and a move queued before the stop
    # starts when the stop ramp ends ([MC] 4.3.134/144's mechanism taken literally; docs/emulator.md 13.3.1)
    stop_drops_pending: bool = False
    # a motion command from the interface while a command-table sequence runs: ends the sequence (True), or runs
    # and lets the sequence go on (False); no source says which (docs/emulator.md 13.6)
    interface_command_ends_sequence: bool = True

    # demand current (1B93h, mA) = moving mass x actual acceleration / force constant
    moving_mass_kg: float = 0.5
    force_constant_n_per_a: float = 10.0

    # VAI Go To Analog Pos (019xh): False = the target is the analog input's position when the command runs;
    # True = it follows X4.4 until another motion replaces it ([MC] 4.3.18 does not say which)
    analog_target_follows: bool = False

    # the trajectory record (drive.mc.trajectory): one sample per MC cycle and per event
    record_trajectory: bool = True

    # position indexing (070xh/071xh, [MC] 4.3.69/70 garbled): the target moves by this many pu per master
    # encoder count counted since the command (INFERRED)
    position_indexing_pu_per_count: float = 1.0

    # winding (304h/305h adaptation, INFERRED): each stroke's reversal position moves inwards by this per stroke
    # adapted before it, plus the disturbance amplitude x frac(k x golden ratio) (a varying reversal point
    # against ribbon patterns); 0: fixed left/right positions
    winding_adaptation_pu_per_stroke: float = 0.0
    winding_disturbance_pu: float = 0.0

    # the force sensor (force control 380xh..385xh, [MC] 4.3.217..222; INFERRED model): a contact at this
    # position (None: nothing to press on), a spring of this stiffness beyond it (pressing towards positive
    # positions), the measured force with Gaussian noise of this standard deviation (seeded: reproducible)
    force_contact_pu: int | None = None
    force_stiffness_n_per_mm: float = 10.0
    force_noise_n: float = 0.0
    force_noise_seed: int = 21
    # the force controller: the demand moves by gain x (target - measured force) per second (pu/(N s)); with
    # the default stiffness the loop settles with a time constant of 1 / (gain x stiffness) = 20 ms
    force_control_gain_pu_per_n_s: float = 50_000.0
    # streams ([MC] 5.4): setpoints received but not yet played that the drive holds; one more is a buffer
    # overflow (0082h). The manual names the error, not the size: 4 is INFERRED (a strictly cyclic master
    # keeps 1..2 ahead with the 1.5-period delay)
    stream_buffer_points: int = 4

    # run quiet cycles (plain motion) in a tight loop and ahead of the bus: a speed-up with the same results
    # (tests/emulator/motion/test_motion_equivalence.py); False runs every cycle through the generic path
    quiet_cycles: bool = True

    def with_(self, **changes) -> MotionSettings:
        return replace(self, **changes)
