"""Where the motion plan lies in the axis' stroke, and where the emulated mechanics must be for it to fit.

The emulated slider has two mechanical stops `MotionSettings.stop_negative_pu/stop_positive_pu` apart (the
stroke) and powers on at `start_position_pu` in its own frame. Homing fixes the drive's frame
(docs/emulator.md, homing): modes 2..5 ([MC] homing modes: mechanical stop / home switch, positive / negative
search; the emulated switch is the stop) set Home Position (13C7h) at that stop; the other modes set it at the
slider's power-on position. A PVL written for a real machine does not describe the machine, so a plan may
lie beyond the emulated stops although nothing in the file is wrong (issue 24: a curve down to -30 mm with the
home, 0 mm, set on the negative stop). The job therefore places the emulated mechanics so that every step lies
within the stroke: the stop's coordinate (the drive's stored 13C7h, as the machine's integrator left it) when
the PVL does not set 13C7h, else the power-on position; it keeps the emulator's defaults when the plan fits
them (the demo's trace stays the same). What cannot fit is said before any motion, with the figures:
a step beyond the PVL's own position limits (146Fh/146Eh, enabled by 1602h), beyond a stop the PVL's own
13C7h fixes, or a plan longer than the stroke.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from linmot_st.emulator import E1100Drive
from linmot_st.emulator.linmot.motion import MotionSettings
from linmot_st.protocol.upids import (
    P_HOME_POSITION,
    P_HOMING_MODE,
    P_INITIAL_POSITION,
    P_LIMIT_NEGATIVE,
    P_LIMIT_POSITIVE,
    P_LIMITS_ENABLE,
)

MM = 10_000                     # 0.1 um per mm
PLACE_MARGIN_MM = 1.0           # a placed stop lies this far beyond the plan's extreme position
SEARCH = {2: +1, 3: -1, 4: +1, 5: -1}    # the emulator's HOMING_SEARCH: the stop homing runs into


@dataclass
class Stroke:
    """The stroke in the drive's frame (mm, after homing) and the emulated mechanics that give it."""
    negative_mm: float
    positive_mm: float
    home_mm: float                          # Home Position (13C7h) the drive homes to
    homing_mode: int
    start_position_pu: int                  # the slider's power-on position in its own frame
    home_position_raw: int | None = None    # the drive's stored 13C7h to set (None: as the drive has it)
    placed: bool = False                    # moved from the emulator's defaults for this plan
    limits: tuple[float, float] | None = None   # enabled position limits (mm), the PVL's or the drive's
    refusals: list[str] = field(default_factory=list)

    def where(self, lo: float, hi: float) -> str:
        """A step's span as a share of the stroke, for the report."""
        length = self.positive_mm - self.negative_mm
        a, b = (lo - self.negative_mm) / length * 100, (hi - self.negative_mm) / length * 100
        return f"{lo:g}..{hi:g} mm ({a:.0f}..{b:.0f} % of the stroke)" if lo != hi else \
            f"{lo:g} mm ({a:.0f} % of the stroke)"

    def describe(self) -> str:
        side = {+1: "positive", -1: "negative"}.get(SEARCH.get(self.homing_mode, 0))
        how = (f"homing (mode {self.homing_mode}) sets {self.home_mm:g} mm on the {side} stop" if side else
               f"homing (mode {self.homing_mode}) sets {self.home_mm:g} mm at the power-on position")
        lim = f"; position limits {self.limits[0]:g}..{self.limits[1]:g} mm" if self.limits else ""
        return (f"stroke {self.negative_mm:g}..{self.positive_mm:g} mm ({how}"
                f"{', placed for this plan' if self.placed else ''}){lim}")

    def settings(self, base=None):
        """The emulated drive's MotionSettings with this power-on position."""
        return (base or MotionSettings()).with_(start_position_pu=self.start_position_pu)

    def store_home(self, drive) -> None:
        """The drive's stored Home Position as placed (before it is switched on; commissioning keeps it, the
        PVL not setting 13C7h)."""
        params = drive.mc.params            # the E1100 UPIDs (a B1100's: the view of its counterparts)
        if self.home_position_raw is not None and P_HOME_POSITION in params:
            params.write(P_HOME_POSITION, self.home_position_raw & 0xFFFFFFFF, ram=True, rom=True)


def _value(pvl, defaults, upid: int) -> tuple[int, bool]:
    """The parameter as the drive will hold it after commissioning: the PVL's value, else the drive's."""
    layer = pvl.layer(2)
    p = layer.get(upid) if layer is not None else None
    if p is not None:
        return p.signed_value, True
    return defaults(upid), False


def drive_defaults():
    """The emulated drive's default of a parameter (its ROM value as delivered)."""
    params = E1100Drive(1).params

    def value(upid: int) -> int:
        raw = params[upid].rom
        return raw - (1 << 32) if raw >= 1 << 31 else raw
    return value


def fit(pvl, spans: list[tuple[int, str, float, float]], settings=None, defaults=None) -> Stroke:
    """Place the emulated mechanics for steps visiting `spans` (step number, label, lowest mm, highest mm;
    the home step not among them: it is where the stroke is fixed)."""
    s = settings or MotionSettings()
    defaults = defaults or drive_defaults()
    length = (s.stop_positive_pu - s.stop_negative_pu) / MM
    mode, _ = _value(pvl, defaults, P_HOMING_MODE)
    home_raw, home_in_pvl = _value(pvl, defaults, P_HOME_POSITION)
    home = home_raw / MM
    initial, _ = _value(pvl, defaults, P_INITIAL_POSITION)
    direction = SEARCH.get(mode)
    if direction is not None:          # homing ends at the initial position
        spans = spans + [(0, "homing's initial position (1502h)", initial / MM, initial / MM)]
    lo = min((a for _, _, a, _ in spans), default=home)
    hi = max((b for _, _, _, b in spans), default=home)
    start = s.start_position_pu
    st = Stroke(0, 0, home, mode, start)
    if direction == -1:
        neg = home
        if not home_in_pvl and not (lo >= neg and hi <= neg + length):
            neg, st.placed = lo - PLACE_MARGIN_MM, True
            st.home_position_raw = round(neg * MM)
        st.negative_mm, st.positive_mm, st.home_mm = neg, neg + length, neg
    elif direction == +1:
        pos = home
        if not home_in_pvl and not (hi <= pos and lo >= pos - length):
            pos, st.placed = hi + PLACE_MARGIN_MM, True
            st.home_position_raw = round(pos * MM)
        st.negative_mm, st.positive_mm, st.home_mm = pos - length, pos, pos
    else:                              # the home is where the slider powered on
        neg = home - (start - s.stop_negative_pu) / MM
        if not (lo >= neg and hi <= neg + length):
            neg, st.placed = lo - PLACE_MARGIN_MM, True
            st.start_position_pu = s.stop_negative_pu + round((home - neg) * MM)
        st.negative_mm, st.positive_mm = neg, neg + length
    enabled, _ = _value(pvl, defaults, P_LIMITS_ENABLE)
    if enabled:
        lneg, neg_pvl = _value(pvl, defaults, P_LIMIT_NEGATIVE)
        lpos, pos_pvl = _value(pvl, defaults, P_LIMIT_POSITIVE)
        st.limits = (lneg / MM, lpos / MM)
        for k, label, a, b in spans:
            if a < st.limits[0]:
                st.refusals.append(f"step {k} ({label}) reaches {a:g} mm, below the negative position limit "
                                   f"{st.limits[0]:g} mm (146Eh, {'the PVL' if neg_pvl else 'the drive default'})")
            if b > st.limits[1]:
                st.refusals.append(f"step {k} ({label}) reaches {b:g} mm, above the positive position limit "
                                   f"{st.limits[1]:g} mm (146Fh, {'the PVL' if pos_pvl else 'the drive default'})")
    for k, label, a, b in spans:
        if a < st.negative_mm or b > st.positive_mm:
            why = ("the plan spans more than the stroke" if hi - lo > length else
                   f"homing sets the PVL's Home Position (13C7h) {home:g} mm on the stop")
            st.refusals.append(f"step {k} ({label}) spans {a:g}..{b:g} mm, beyond the stroke "
                               f"{st.negative_mm:g}..{st.positive_mm:g} mm ({length:g} mm; {why})")
    return st
