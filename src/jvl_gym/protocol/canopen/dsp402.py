"""The DSP-402 drive of a node (MIS manual §11.5): the controlword/statusword state machine,
the modes of operation and the factors, carried out with the motor's own registers.

**State machine** (DSP-402; statusword bits 0–6: ready to switch on, switched on, operation
enabled, fault, voltage enabled, quick stop, switch on disabled (the state's value carries bits
0–3, 5 and 6); bit 9 remote; bit 11 internal limit active (607Dh, below); bit 7, warning, is
not used). Commands of the controlword: shutdown
(xxxx x110), switch on (xxxx x111), disable voltage (xxxx xx0x), quick stop (xxxx x01x), disable
operation (xxxx 0111), enable operation (xxxx 1111), fault reset (bit 7 rising). Every
transition 2–16; after power-on the drive is SWITCH ON DISABLED. Entering OPERATION ENABLED puts
the motor in the mode's MODE_REG; leaving it makes it passive. Quick stop decelerates at 6085h
(velocity mode, V_SOLL 0), then by the quick stop option code 605Ah (0: at once, 1–3: after the
stop, 5–7: stays) goes to SWITCH ON DISABLED. A motor error (ERR_BITS ≠ 0) in any state is the
fault reaction: the motor is made passive and the drive is FAULT; a fault reset clears the
motor's errors (command 97) and, if none remains, leads to SWITCH ON DISABLED. "The start mode
of the motor must be set to passive" (§11.5.1): the drive assumes it.

**Modes** (6060h → 6061h; changed only while operation is not enabled, §11.5.3, except from
homing to profile position once the homing is done):

=====  =====================  =============================================================
1      profile position       bit 4 new set-point (rising), 5 change set immediately,
       §11.5.4                6 relative, 8 halt; status bit 12 set-point acknowledge,
                              10 target reached. Target 607Ah, 6081h, 6083h, 6084h →
                              P_SOLL, V_SOLL, A_SOLL, D_SOLL (MODE_REG position)
3      profile velocity       60FFh → V_SOLL in velocity mode, 6083h/6084h; bit 8 halt;
       §11.5.5                status 10 velocity reached, 12 velocity zero
4      profile torque         as 3, with RUN_CURRENT = its value at the start × min(6071h,
       §11.5.7                6072h)/1000, ramped at 6087h ‰/s
6      homing §11.5.6         bit 4 start: the methods of :mod:`.homing` as the motor's
                              zero searches; status 12 homing attained, 13 homing error,
                              10 target reached
7      interpolated position  bit 4 enable IP; at each SYNC to 60C1h sub 1 (absolute, or
       §11.5.8                relative when sub 2 = 1) within the period 60C2h; status 10
8      cyclic sync position   bit 4 enable CSP, 6 relative; every target 607Ah written (an
       §11.5.9                RPDO of a synchronous type: at the SYNC) is reached within the
                              period 60C2h with no ramp; status 10 CSP ready
9      cyclic sync velocity   60FFh at once, no ramp; polarity 607Eh bit 6 reverses it
10     cyclic sync torque     velocity mode at 6080h (polarity) with the current of 6071h
=====  =====================  =============================================================

**Software position limit** (607Dh; §11.5.1 lists it, the manual says no more; CiA 402:
the limits bound the position demand, every new target is checked against them): in the
position modes (profile position, interpolated position, cyclic synchronous position) a
target beyond sub 1 (min) or sub 2 (max), in user units, is limited to that limit — the move
ends at the limit — and statusword bit 11 (internal limit active) is set while the target in
force was limited. The velocity and torque modes are not limited by 607Dh (the motor's own
MIN_P_IST/MAX_P_IST, §5.9, apply in every mode).

**Factors** (§11.5.2): position in user units = counts × feed (6092h sub 1 / sub 2) / (gear
6091h sub 1 / sub 2 × counts per revolution), so with the defaults (gear 1/1, feed 409 600/1)
user units are counts; velocity: V_SOLL units (0.01 RPM) = user × 6094h sub 1 / sub 2;
acceleration: A_SOLL units (RPM/s) = user × 6097h sub 1 / sub 2.
"""

from __future__ import annotations

import enum
import math
from fractions import Fraction
from typing import Any

from canopen.sdo import SdoAbortedError

from . import emcy
from .homing import METHODS, Method, Search
from .objects import HOMING_METHODS, SUPPORTED_MODES
from .sdo import ABORT

__all__ = ["Drive", "State", "STATUS_BITS"]


class State(enum.Enum):
    """DSP-402 states and their statusword bits 0–6."""

    NOT_READY = 0x00
    SWITCH_ON_DISABLED = 0x40
    READY_TO_SWITCH_ON = 0x21
    SWITCHED_ON = 0x23
    OPERATION_ENABLED = 0x27
    QUICK_STOP_ACTIVE = 0x07
    FAULT_REACTION_ACTIVE = 0x0F
    FAULT = 0x08


#: statusword bits besides the state (DSP-402)
STATUS_BITS = {"voltage": 1 << 4, "remote": 1 << 9, "target": 1 << 10,
               "limit": 1 << 11, "bit12": 1 << 12, "bit13": 1 << 13}
_PP, _PV, _PT, _HM, _IP, _CSP, _CSV, _CST = 1, 3, 4, 6, 7, 8, 9, 10
_A_MAX = 500000  # A_SOLL range (RPM/s), the "close to no ramp" of the cyclic modes


class Drive:
    """The DSP-402 drive of ``node`` (a :class:`~.slave.CanopenSlave`)."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.f = node.facts
        self.power_on()

    def power_on(self) -> None:
        """After power-on and reset node: SWITCH ON DISABLED, mode 0, nothing pending."""
        self.state = State.SWITCH_ON_DISABLED
        self.controlword = 0
        self.mode = 0
        self.ack = False
        self.target_reached = True
        self.queued: int | None = None
        self.homing: str | None = None  # None, "running", "attained", "error"
        self.homing_plan: Method | None = None  # the method under way
        self.homing_seeking = False  # its first search onto the home switch is under way
        self.user_zs_bits: int | None = None  # ZERO_SEARCH_BITS as the user left it
        self.halted = False
        self.base_current = 0
        self.current = 0.0
        self.ip_enabled = False
        self.last_target_counts = 0
        self.limited = False  # the target in force was limited by 607Dh

    # ------------------------------------------------------------------ registers
    def _r(self, reg: int) -> int:
        return self.node.reg_read(reg)

    def _w(self, reg: int, value: int) -> None:
        self.node.reg_write(reg, int(value))

    def _v(self, index: int, sub: int = 0) -> int:
        return int(self.node.value(index, sub))

    # ------------------------------------------------------------------ factors
    def _pos_factor(self) -> Fraction:
        """Counts per user position unit (§11.5.2)."""
        gear = Fraction(self._v(0x6091, 1), self._v(0x6091, 2))
        feed = Fraction(self._v(0x6092, 1), self._v(0x6092, 2))
        return gear * self.f.counts_per_rev / feed

    def counts(self, user: int) -> int:
        """User position → counts."""
        return round(user * self._pos_factor())

    def user_position(self, counts: int) -> int:
        """Counts → user position."""
        return round(counts / self._pos_factor())

    def velocity(self, user: int) -> int:
        """User velocity → V_SOLL units, within V_SOLL's range."""
        v = round(user * Fraction(self._v(0x6094, 1), self._v(0x6094, 2)))
        return max(-300000, min(300000, v))

    def user_velocity(self, v: int) -> int:
        return round(v / Fraction(self._v(0x6094, 1), self._v(0x6094, 2)))

    def within_limits(self, goal: int) -> int:
        """Position target ``goal`` [counts] limited to the software position limits 607Dh
        (module text); notes whether it was."""
        lo = self.counts(self._v(0x607D, 1))
        hi = self.counts(self._v(0x607D, 2))
        limited = min(max(goal, lo), hi) if lo <= hi else goal
        self.limited = limited != goal
        return limited

    def acceleration(self, user: int) -> int:
        a = round(user * Fraction(self._v(0x6097, 1), self._v(0x6097, 2)))
        return max(1, min(_A_MAX, a))

    # ------------------------------------------------------------------ statusword
    def statusword(self) -> int:
        """6041h now."""
        sw = self.state.value | STATUS_BITS["remote"]
        if self.state in (State.READY_TO_SWITCH_ON, State.SWITCHED_ON,
                          State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE):
            sw |= STATUS_BITS["voltage"]
        if self.state != State.OPERATION_ENABLED:
            return sw | (STATUS_BITS["target"] if self.mode != _HM or self.homing else 0)
        if self.limited and self.mode in (_PP, _IP, _CSP):
            sw |= STATUS_BITS["limit"]
        if self.mode == _PP:
            sw |= STATUS_BITS["bit12"] if self.ack else 0
            sw |= STATUS_BITS["target"] if self._pp_reached() else 0
        elif self.mode in (_PV, _PT, _CSV, _CST):
            v = self._r(self.f.v_ist)
            target = 0 if self.halted else self._r(self.f.v_soll)
            sw |= STATUS_BITS["target"] if v == target else 0
            sw |= STATUS_BITS["bit12"] if v == 0 else 0
        elif self.mode == _HM:
            if self.homing == "attained":
                sw |= STATUS_BITS["bit12"] | STATUS_BITS["target"]
            elif self.homing == "error":
                sw |= STATUS_BITS["bit13"] | STATUS_BITS["target"]
            elif self.homing is None:
                sw |= STATUS_BITS["target"]
        elif self.mode in (_IP, _CSP):
            if self.ip_enabled:
                sw |= STATUS_BITS["target"] | STATUS_BITS["bit12"]
        return sw

    def _pp_reached(self) -> bool:
        if self.queued is not None:
            return False
        if self.halted:
            return self._r(self.f.v_ist) == 0
        return (self._r(self.f.mode) == self.f.position
                and self._r(self.f.p_ist) == self._r(self.f.p_soll)
                and bool(self._r(self.f.statusbits) & self.f.st_in_position))

    # ------------------------------------------------------------------ objects
    def write_mode(self, mode: int) -> None:
        """6060h := ``mode`` (§11.5.3)."""
        if mode != 0 and mode not in SUPPORTED_MODES:
            raise SdoAbortedError(ABORT["range"])
        if self.state == State.OPERATION_ENABLED and mode != self.mode:
            if not (self.mode == _HM and mode == _PP and self.homing == "attained"):
                raise SdoAbortedError(ABORT["state"])
            self.mode = mode
            self._enter_mode()
            return
        self.mode = mode
        self.homing = None

    def write_homing_method(self, method: int) -> None:
        """6098h: the methods of :mod:`.homing`; 0 = none."""
        if method != 0 and method not in HOMING_METHODS:
            raise SdoAbortedError(ABORT["range"])

    def write_target_position(self, value: int) -> None:
        """607Ah written (by SDO or RPDO): in CSP it is the next cyclic set-point."""
        if self.mode == _CSP and self.state == State.OPERATION_ENABLED and self.ip_enabled:
            relative = bool(self.controlword & (1 << 6))
            self._cyclic_move(self.counts(value), relative)

    def write_target_velocity(self, value: int) -> None:
        """60FFh written: profile velocity and CSV follow it at once."""
        if self.state == State.OPERATION_ENABLED and self.mode in (_PV, _PT, _CSV):
            self._velocity_setpoint()

    # ------------------------------------------------------------------ controlword
    def write_controlword(self, cw: int) -> None:
        """6040h := ``cw``: the state machine's transition, then the mode's bits."""
        old, self.controlword = self.controlword, cw
        s = self.state
        low = cw & 0x8F
        if s == State.FAULT:
            if cw & 0x80 and not old & 0x80:
                self._w(self.f.command, self.f.cmd_clear_errors)
                if not self._r(self.f.err_bits):
                    self.state = State.SWITCH_ON_DISABLED
            return
        if s in (State.FAULT_REACTION_ACTIVE, State.NOT_READY):
            return
        disable_voltage = not cw & 0x02
        quick_stop = (cw & 0x06) == 0x02
        shutdown = (low & 0x87) == 0x06
        switch_on = low == 0x07  # "disable operation" from enabled
        enable = low == 0x0F
        if s == State.SWITCH_ON_DISABLED:
            if shutdown:
                self.state = State.READY_TO_SWITCH_ON
        elif s == State.READY_TO_SWITCH_ON:
            if disable_voltage or quick_stop:
                self.state = State.SWITCH_ON_DISABLED
            elif switch_on:
                self.state = State.SWITCHED_ON
            elif enable:  # xxxx x111 switches on (transition 3), then enables (4)
                self.state = State.SWITCHED_ON
                self._enable()
        elif s == State.SWITCHED_ON:
            if disable_voltage or quick_stop:
                self.state = State.SWITCH_ON_DISABLED
            elif shutdown:
                self.state = State.READY_TO_SWITCH_ON
            elif enable:
                self._enable()
        elif s == State.OPERATION_ENABLED:
            if disable_voltage:
                self._disable(State.SWITCH_ON_DISABLED)
            elif quick_stop:
                self._quick_stop()
            elif shutdown:
                self._disable(State.READY_TO_SWITCH_ON)
            elif switch_on:
                self._disable(State.SWITCHED_ON)
            else:
                self._mode_bits(old, cw)
        elif s == State.QUICK_STOP_ACTIVE:
            if disable_voltage:
                self._disable(State.SWITCH_ON_DISABLED)
            elif enable and self._v(0x605A) in (5, 6, 7, 8):
                self.state = State.OPERATION_ENABLED
                self._enter_mode()

    def _enable(self) -> None:
        self.state = State.OPERATION_ENABLED
        self._enter_mode()

    def _disable(self, state: State) -> None:
        self.state = state
        if self.homing == "running":  # interrupted
            self._end_homing("error")
        self.ip_enabled = False
        self.queued = None
        self.ack = False
        self._passive()
        if self.base_current:
            self._w(self.f.run_current, self.base_current)
            self.base_current = 0

    def _passive(self) -> None:
        if self._r(self.f.mode) != self.f.passive:
            self._w(self.f.mode, self.f.passive)

    def _quick_stop(self) -> None:
        self.state = State.QUICK_STOP_ACTIVE
        if self._v(0x605A) == 0:
            self._disable(State.SWITCH_ON_DISABLED)
            return
        self._w(self.f.a_soll, self.acceleration(self._v(0x6085)))
        self._w(self.f.v_soll, 0)
        self._w(self.f.mode, self.f.velocity)

    def _enter_mode(self) -> None:
        """The motor's mode for 6060h as operation is enabled (holding its position)."""
        m = self.mode
        self.halted = bool(self.controlword & 0x100)
        self.ack = False
        self.queued = None
        self.limited = False
        self.last_target_counts = self._r(self.f.p_ist)
        if m in (_PP, _IP, _CSP, _HM, 0):
            self._w(self.f.p_soll, self.last_target_counts)
            if m in (_IP, _CSP):
                self._w(self.f.a_soll, _A_MAX)
                self._w(self.f.d_soll, _A_MAX)
            self._w(self.f.mode, self.f.position)
            self.ip_enabled = m in (_IP, _CSP) and bool(self.controlword & 0x10)
        elif m in (_PV, _PT, _CSV, _CST):
            if m in (_PT, _CST):
                self.base_current = self._r(self.f.run_current)
                self.current = 0.0 if m == _PT else self._torque_current()
                self._w(self.f.run_current, round(self.current))
            self._velocity_setpoint()
            self._w(self.f.mode, self.f.velocity)

    def _torque_current(self) -> float:
        permille = min(self._v(0x6071), self._v(0x6072))
        return self.base_current * permille / 1000.0

    def _velocity_setpoint(self) -> None:
        m = self.mode
        if m == _CST:
            v = self.velocity(self._v(0x6080))
        else:
            v = 0 if self.halted else self.velocity(self._v(0x60FF))
        if m in (_CSV, _CST):
            if self._v(0x607E) & 0x40:
                v = -v
            self._w(self.f.a_soll, _A_MAX)
            self._w(self.f.d_soll, _A_MAX)
        else:
            self._w(self.f.a_soll, self.acceleration(self._v(0x6083)))
            dec = self._v(0x6084)
            self._w(self.f.d_soll, self.acceleration(dec) if dec else 0)
        self._w(self.f.v_soll, v)

    def _mode_bits(self, old: int, cw: int) -> None:
        rising = cw & ~old
        halt = bool(cw & 0x100)
        m = self.mode
        if m == _PP:
            if halt != self.halted:
                self.halted = halt
                if halt:
                    self._w(self.f.v_soll, 0)
                    self._w(self.f.mode, self.f.velocity)
                else:
                    self._start_move(self.last_target_counts)
            if rising & 0x10 and not halt:
                target = self.counts(self._v(0x607A))
                base = (self.last_target_counts if cw & 0x40 else 0)
                goal = base + target
                moving = self.queued is not None or (
                    self._r(self.f.mode) == self.f.position
                    and self._r(self.f.p_ist) != self._r(self.f.p_soll))
                if cw & 0x20 or not moving:
                    self._start_move(goal)
                    self.ack = True
                else:  # acknowledged when the move under way ends (§11.5.4, t6)
                    self.queued = goal
            if not cw & 0x10 and self.queued is None:
                self.ack = False
        elif m in (_PV, _PT):
            if halt != self.halted:
                self.halted = halt
                self._velocity_setpoint()
        elif m == _HM:
            if rising & 0x10:
                self._start_homing()
            elif halt and self.homing == "running":
                self._end_homing("error")
        elif m in (_IP, _CSP):
            enabled = bool(cw & 0x10)
            if enabled and not self.ip_enabled:
                self.last_target_counts = self._r(self.f.p_soll)
            self.ip_enabled = enabled

    def _start_move(self, goal: int) -> None:
        goal = self.within_limits(goal)
        self.last_target_counts = goal
        self._w(self.f.v_soll, max(1, abs(self.velocity(self._v(0x6081)))))
        self._w(self.f.a_soll, self.acceleration(self._v(0x6083)))
        dec = self._v(0x6084)
        self._w(self.f.d_soll, self.acceleration(dec) if dec else 0)
        if self._r(self.f.mode) != self.f.position:
            self._w(self.f.p_soll, self._r(self.f.p_ist))
            self._w(self.f.mode, self.f.position)
        self._w(self.f.p_soll, goal)

    def _start_homing(self) -> None:
        """Bit 4 rising in homing mode: the method's first search (onto the home switch,
        when it has one and the switch is not active) or its final search (:mod:`.homing`)."""
        method = self._v(0x6098)
        plan = METHODS.get(method)
        if plan is None:
            self.homing = "error"
            self.node.emergency(emcy.HOMING_PROFILE)
            return
        self._w(self.f.v_home_crawl, abs(self.velocity(self._v(0x6099, 2))))
        # the homing acceleration 609Ah for the starts and the stops of the searches
        self._w(self.f.a_soll, self.acceleration(self._v(0x609A)))
        self._w(self.f.d_soll, self.acceleration(self._v(0x609A)))
        if self.f.zero_search_bits is not None and self.user_zs_bits is None:
            self.user_zs_bits = self._r(self.f.zero_search_bits)
        self.homing_plan = plan
        self.homing = "running"
        on_switch = bool(self._r(self.f.inputs) & self._r(self.f.home_mask))
        self.homing_seeking = bool(plan.seek) and not on_switch
        if self.homing_seeking:
            # on to the home switch, turning at a limit switch; the zero found is passing
            kept = (self.user_zs_bits or 0) & self.f.zs_no_time_out
            self._search(Search(False, plan.seek), self.f.zs_turn_at_limit | kept, 0)
        else:
            self._final_search(plan)

    def _final_search(self, plan: Method) -> None:
        """The method's last search: the switch edge, then (with the index) on to it."""
        final = plan.final
        if final.torque:
            self._w(self.f.home_mask, 0)
        options = 0
        if self.user_zs_bits is not None:
            f = self.f
            kept = f.zs_no_time_out | (f.zs_turn_at_limit | f.zs_opposite_side
                                       if plan.user_options else 0)
            options = self.user_zs_bits & kept
            options |= f.zs_use_index if plan.index else 0
            options |= f.zs_opposite_side if final.opposite else 0
            options |= f.zs_ignore_switch if final.ignore_switch else 0
        self._search(final, options, self.counts(self._v(0x607C)))

    def _search(self, search: Search, options: int, p_home: int) -> None:
        """Start the motor's zero search ``search`` with ZERO_SEARCH_BITS ``options`` and
        the zero at ``p_home`` counts."""
        self._w(self.f.v_home,
                search.direction * max(1, abs(self.velocity(self._v(0x6099, 1)))))
        self._w(self.f.p_home, p_home)
        if self.f.zero_search_bits is not None:
            self._w(self.f.zero_search_bits, options)
        self._w(self.f.mode, self.f.zero_search_2 if search.type2 else self.f.zero_search_1)

    def _end_homing(self, outcome: str) -> None:
        """The homing ends (``outcome``: "attained" or "error"): the motor holds its position
        in position mode and ZERO_SEARCH_BITS is the user's again."""
        self.homing = outcome
        self.homing_plan = None
        self.homing_seeking = False
        if self.user_zs_bits is not None:
            self._w(self.f.zero_search_bits, self.user_zs_bits)
            self.user_zs_bits = None
        if self.state == State.OPERATION_ENABLED:
            self._w(self.f.p_soll, self._r(self.f.p_ist))
            self._w(self.f.mode, self.f.position)

    def _cyclic_move(self, counts: int, relative: bool) -> None:
        """Reach ``counts`` (or that much further) within one interpolation period."""
        goal = self.within_limits(self.last_target_counts + counts if relative else counts)
        period_ms = max(1, self._v(0x60C2, 1))
        delta = abs(goal - self._r(self.f.p_ist))
        # the speed that covers the step in the period less two samples (the motor's 1 ms
        # samples of the start and the end of the step's short ramp)
        span = max(1, period_ms - 2)
        rpm100 = math.ceil(delta * 60000 * 100 / (self.f.counts_per_rev * span))
        self._w(self.f.v_soll, max(1, min(300000, rpm100)))
        self._w(self.f.p_soll, goal)
        self.last_target_counts = goal

    def on_sync(self) -> None:
        """A SYNC: the next segment of interpolated position mode (§11.5.8)."""
        if self.mode == _IP and self.state == State.OPERATION_ENABLED and self.ip_enabled:
            self._cyclic_move(self.counts(self._v(0x60C1, 1)), bool(self._v(0x60C1, 2)))

    # ------------------------------------------------------------------ time
    def tick(self, dt_ms: int) -> None:
        """The drive after ``dt_ms`` more milliseconds: fault reaction, quick stop end,
        profile queue, homing end, torque ramp."""
        err = self._r(self.f.err_bits)
        if err and self.state not in (State.FAULT, State.FAULT_REACTION_ACTIVE):
            self.state = State.FAULT_REACTION_ACTIVE
            self._disable(State.FAULT)
            if self.homing == "running":
                self._end_homing("error")
            return
        if self.state == State.QUICK_STOP_ACTIVE:
            if self._r(self.f.v_ist) == 0 and self._v(0x605A) in (1, 2, 3):
                self._disable(State.SWITCH_ON_DISABLED)
            return
        if self.state != State.OPERATION_ENABLED:
            return
        if self.mode == _PP and self.queued is not None and (
                self._r(self.f.p_ist) == self._r(self.f.p_soll)):
            goal = self.queued
            self.queued = None
            self._start_move(goal)
            self.ack = bool(self.controlword & 0x10)
        elif self.mode == _HM and self.homing == "running":
            if self._r(self.f.mode) not in (self.f.zero_search_1, self.f.zero_search_2):
                ok = not err and bool(self._r(self.f.statusbits) & self.f.st_zero_search_done)
                if ok and self.homing_seeking and self.homing_plan is not None:
                    self.homing_seeking = False
                    self._final_search(self.homing_plan)
                else:
                    self._end_homing("attained" if ok else "error")
        elif self.mode == _PT:
            goal = self._torque_current()
            step = self._v(0x6087) * self.base_current / 1000.0 * dt_ms / 1000.0
            if self.current != goal:
                self.current = (min(goal, self.current + step) if goal > self.current
                                else max(goal, self.current - step))
                self._w(self.f.run_current, round(self.current))

    def torque_demand(self) -> int:
        """6074h/6077h: the commanded current in ‰ of the current at the mode's start."""
        if not self.base_current:
            return 0
        return round(1000 * self.current / self.base_current)
