"""The family contract: what every layer may know of a motor family, stated once.

A family is one folder ``families/<key>/`` whose package defines ``FAMILY``, a :class:`Family`
record. Every generic layer reaches the family through that record and nothing else:

=================  ==========================================================================
engine             ``compiled`` (the step the engine binds) and ``array_class``
                   (the family's :class:`~jvl_gym.MotorArray` subclass)
registers, units   ``table`` (the register table), ``constants`` (modes, bits, scalings),
                   ``units`` (sample rates, counts per revolution, unit conversions)
configs            ``config``: a module of the names of :class:`FamilyConfig`
capabilities       ``capabilities``: the :class:`Capability` members the family supports; a
                   layer asks ``family.supports(...)``, never a list of family keys or
                   ``getattr`` on the motor array
twin               ``twin``: a :class:`TwinSpec` (MacTalk dialects, safe and init modes,
                   status bits by name, user command numbers)
tasks              ``task``: the task interface module (the names of ``__all__`` a compiled
                   task may use, ``FAMILY_KEY``, ``DEFAULT_MOTOR_TYPE``, ``TERMINAL_ERRORS``)
tuning             ``tuning``: a :class:`TuningSpec` (the strategy and the facts it needs) or
                   None where the family has no tuning procedure
programs           ``programs``: the family's stored-program module (:attr:`Family.programs`)
                   or None
CANopen            ``canopen``: a :class:`CanopenSpec` (registers, bits, commands, identity
                   of the CANopen slave) or None
=================  ==========================================================================

Operations a motor array offers under one name and one signature for every family are declared
on :class:`~jvl_gym.MotorArray`; one that a family lacks raises :class:`UnsupportedOperation`
naming the :class:`Capability`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

from .capability import Capability, UnsupportedOperation
from .twin_spec import TwinSpec

if TYPE_CHECKING:
    from ..registers import RegisterTable
    from ..registers.conformance import Conformance
    from ..registers.statements import Statements

__all__ = ["Capability", "UnsupportedOperation", "FamilyConfig", "TwinSpec", "TuningSpec",
           "CanopenSpec", "Family", "MODULES"]

#: the public modules of a family package, by the :class:`Family` field that holds each
MODULES = ("compiled", "constants", "units", "config", "task", "table", "programs")


@runtime_checkable
class FamilyConfig(Protocol):
    """The names a family's ``config`` module exports (the module satisfies this protocol).

    Attributes
    ----------
    MOTORS_DIR : Path
        The folder of the motor configs (``configs/motors``), one YAML file per motor type.
    SETUPS_DIR : Path or None
        The folder of the default setups (``configs/setups``), register sets by name; None
        where the family has none.
    """

    MOTORS_DIR: Path
    SETUPS_DIR: Path | None

    def load_motor(self, motor: Any) -> Any:
        """The validated config of a motor type name, a config path or a config object;
        ``ConfigError`` naming the known types otherwise."""

    def motor_types(self) -> list[str]:
        """Names of the family's motor types (one config each)."""

    def canonical_motor_name(self, name: str) -> str:
        """The motor-type name a user's spelling stands for."""

    def setup_path(self, name: str) -> Path:
        """The file of the default setup ``name`` (a motor config's ``setup``)."""


def filter_taps(table: RegisterTable, prefix: str) -> tuple[str, ...]:
    """Register names ``<prefix><digit>`` in ``table``, highest digit first."""
    names = [reg.name for reg in table if re.fullmatch(prefix + r"\d", reg.name)]
    return tuple(sorted(names, key=lambda n: -int(n[len(prefix):])))


@dataclass(frozen=True)
class TuningSpec:
    """What the tuning toolkit needs of a family: its strategy and the facts it works with.

    Attributes
    ----------
    strategy : str
        Key of the tuning strategy (``"testu_pi"``: TESTU/TESTA records and a PI speed loop
        in the fourth-order filter; ``"buffer_sixth_order"``: sample-buffer records of torque
        steps and the sixth-order main filter).
    implementation : str or None
        ``"package.module:Name"`` of a strategy object the toolkit loads with importlib
        instead of a built-in one for :attr:`strategy` (a family outside the package brings
        its own); None: the toolkit's strategy of that key.
    inner_dt, outer_dt : float
        Current-loop and servo sample times [s].
    inner_per_outer : int
        Current-loop samples per servo sample.
    counts_per_rev : int
        Encoder counts per revolution.
    pwm_full : int
        UA_VAL … full scale ↔ half the supply (bus) voltage [PWM counts].
    amplitude_vf : int
        VF_OUT at which the phase current amplitude is AMPLITUDE ADC counts: 1 where AMPLITUDE
        is a fixed-point gain per VF_OUT unit, VF_FULL where it is an integer number of ADC
        counts at peak torque.
    ff_keys, vb_keys, vfx_keys, vfy_keys : tuple of str
        The speed filter's taps in the table, highest number first: FF and VB numerator taps
        of delay 0, 1, …; VF numerator taps of delay 0, 1, …; VF denominator taps of delay
        1, 2, ….
    vb_gain_register : str or None
        The register that scales V_IST into the speed error's unit (GEARB), None where the
        firmware scales it by :attr:`speed_units`.
    speed_units : float
        Speed registers' unit per count/sample (V_SOLL, FNC_OUT, the speed error: 1/16
        count/sample).
    """

    strategy: str
    inner_dt: float
    outer_dt: float
    inner_per_outer: int
    counts_per_rev: int
    pwm_full: int
    amplitude_vf: int
    ff_keys: tuple[str, ...]
    vb_keys: tuple[str, ...]
    vfx_keys: tuple[str, ...]
    vfy_keys: tuple[str, ...]
    vb_gain_register: str | None
    speed_units: float = 16.0
    implementation: str | None = None

    @property
    def filter_order(self) -> int:
        """Order of the speed (main) filter VF: the number of its numerator taps."""
        return len(self.vfx_keys)

    @property
    def counts_per_rad(self) -> float:
        """Encoder counts per radian."""
        return self.counts_per_rev / (2.0 * math.pi)

    @classmethod
    def of(cls, strategy: str, constants: Any, table: RegisterTable,
           implementation: str | None = None) -> TuningSpec:
        """The spec of a family from its ``constants`` (``INNER_DT``, ``OUTER_DT``,
        ``INNER_PER_OUTER``, ``COUNTS_PER_REV``, ``PWM_FULL``, ``VF_FULL``) and register
        ``table``: the filter taps are its KFF, KVB, KVFX and KVFY registers, AMPLITUDE is a
        gain per VF_OUT unit where its format is fixed-point, and V_IST is scaled by GEARB
        where the table has it (MAC050–141 manual 3.2.89–3.2.111, 3.2.127; MAC800 register
        overview §1.2, registers 121–143 and 174)."""
        from ..registers import Format

        amp_fixed = table.lookup("AMPLITUDE").format in (Format.FIXED4, Format.FIXED8,
                                                         Format.FIXED16, Format.FIXED24)
        return cls(strategy=strategy, inner_dt=constants.INNER_DT, outer_dt=constants.OUTER_DT,
                   inner_per_outer=constants.INNER_PER_OUTER,
                   counts_per_rev=constants.COUNTS_PER_REV, pwm_full=constants.PWM_FULL,
                   amplitude_vf=1 if amp_fixed else constants.VF_FULL,
                   ff_keys=filter_taps(table, "KFF"), vb_keys=filter_taps(table, "KVB"),
                   vfx_keys=filter_taps(table, "KVFX"), vfy_keys=filter_taps(table, "KVFY"),
                   vb_gain_register="GEARB" if "GEARB" in table else None,
                   implementation=implementation)



@dataclass(frozen=True)
class CanopenSpec:
    """What a CANopen slave (CiA DS-301/DSP-402) of a family's motors uses: registers, bits,
    modes, commands and identity, stated by the family (``Family.canopen``).

    Register attributes hold register names as the family states them;
    :meth:`numbered` gives the same record with the numbers of a register table.

    Attributes
    ----------
    node_id, baud : str or int
        Node id and bit-rate code registers.
    mode, p_soll, v_soll, a_soll, d_soll, p_ist, v_ist, flwerr, flwerrmax : str or int
        The mode register and the profile registers.
    err_bits, statusbits, command, inputs, outputs, setup_bits : str or int
        Error bits, status bits, the command register, the digital inputs and outputs and the
        setup bits.
    run_current, home_mask, nl_mask, pl_mask, v_home, v_home_crawl, p_home, t_home : str or int
        Running current and the zero search registers.
    motor_type, serial, version, hardware : str or int
        Identity registers.
    passive, velocity, position, zero_search_1, zero_search_2 : int
        Mode-register values.
    st_in_position, st_at_velocity, st_zero_search_done : int
        Status-bit masks.
    err_general, err_follow, err_low_bus, err_position, err_zero_search_timeout : int
        Error-bit masks.
    cmd_clear_errors, cmd_save : int
        Command numbers: clear errors, save to flash and continue.
    beckhoff_bit : int
        The setup bit that selects the Beckhoff variant of the DSP-402 state machine.
    counts_per_rev : int
        Position counts per revolution (object 608Fh).
    vendor_id, device_type : int
        Objects 1018h sub-index 1 and 1000h.
    device_name : str
        Object 1008h (and the manufacturer objects 6404h, 6504h).
    motor_name : str
        Object 6402h, the motor type.
    product_name : str
        The EDS file's product name.
    eds : Path or None
        The family's EDS file (the object dictionary the slave serves, as a file for a
        master), or None.
    zero_search_bits : str, int or None
        The zero search's option register (None: the family has none; the DSP-402 homing
        methods that need its options are then refused).
    zs_use_index, zs_turn_at_limit, zs_opposite_side, zs_ignore_switch, zs_no_time_out : int
        Its option bits: on to the encoder index, turn at a limit input, the sensor's far
        side, no sensor, no time-out.
    """

    node_id: str | int
    baud: str | int
    mode: str | int
    p_soll: str | int
    v_soll: str | int
    a_soll: str | int
    d_soll: str | int
    p_ist: str | int
    v_ist: str | int
    flwerr: str | int
    flwerrmax: str | int
    err_bits: str | int
    statusbits: str | int
    command: str | int
    inputs: str | int
    outputs: str | int
    setup_bits: str | int
    run_current: str | int
    home_mask: str | int
    nl_mask: str | int
    pl_mask: str | int
    v_home: str | int
    v_home_crawl: str | int
    p_home: str | int
    t_home: str | int
    motor_type: str | int
    serial: str | int
    version: str | int
    hardware: str | int
    passive: int
    velocity: int
    position: int
    zero_search_1: int
    zero_search_2: int
    st_in_position: int
    st_at_velocity: int
    st_zero_search_done: int
    err_general: int
    err_follow: int
    err_low_bus: int
    err_position: int
    err_zero_search_timeout: int
    cmd_clear_errors: int
    cmd_save: int
    beckhoff_bit: int
    counts_per_rev: int
    vendor_id: int
    device_type: int
    device_name: str
    motor_name: str
    product_name: str
    eds: Path | None = None
    zero_search_bits: str | int | None = None
    zs_use_index: int = 0
    zs_turn_at_limit: int = 0
    zs_opposite_side: int = 0
    zs_ignore_switch: int = 0
    zs_no_time_out: int = 0

    #: the attributes that name registers
    REGISTER_FIELDS: ClassVar[tuple[str, ...]] = (
        "node_id", "baud", "mode", "p_soll", "v_soll", "a_soll", "d_soll", "p_ist", "v_ist",
        "flwerr", "flwerrmax", "err_bits", "statusbits", "command", "inputs", "outputs",
        "setup_bits", "run_current", "home_mask", "nl_mask", "pl_mask", "v_home",
        "v_home_crawl", "p_home", "t_home", "motor_type", "serial", "version", "hardware")
    #: the attributes that name registers a family may lack (None)
    OPTIONAL_REGISTER_FIELDS: ClassVar[tuple[str, ...]] = ("zero_search_bits",)

    def numbered(self, table: RegisterTable) -> CanopenSpec:
        """This record with every register name replaced by its number in ``table``.

        Raises
        ------
        ValueError
            The table lacks a register the slave needs (naming it).
        """
        from ..registers import RegisterError

        numbers = {}
        for name in self.REGISTER_FIELDS + self.OPTIONAL_REGISTER_FIELDS:
            key = getattr(self, name)
            if key is None:
                continue
            try:
                numbers[name] = table.lookup(key).number
            except RegisterError:
                raise ValueError(f"the motors' register table has no {key} register, which "
                                 "the CANopen slave needs") from None
        return replace(self, **numbers)


@dataclass(frozen=True)
class Family:
    """A motor family as every layer sees it (``FAMILY`` of the family's package).

    Attributes
    ----------
    key : str
        Identifier (``"mac050_141"``), also used in compiled-cache file names.
    title : str
        Human name (``"MAC050–141 integrated servo motors"``).
    compiled : module
        The compiled step: ``outer_sample``, ``inner_block``, ``LANES``, ``scratch`` (see
        :mod:`jvl_gym.engine.driver`) and ``compile_split`` or ``prepare``
        (:mod:`jvl_gym.engine.two_cores`).
    array_class : type
        The family's :class:`~jvl_gym.MotorArray` subclass.
    table : RegisterTable
        The register table.
    constants : module
        Modes, status and control bits, scalings (``constants.py``).
    units : module
        Sample rates, counts per revolution and unit conversions (``units.py``).
    config : FamilyConfig
        The motor configs and default setups (``config.py``).
    task : module
        The task interface (``task.py``).
    twin : TwinSpec
        What the digital twin needs.
    capabilities : frozenset of Capability
        What the family supports.
    tuning : TuningSpec or None
        The tuning strategy and its facts; None: no tuning procedure.
    conformance : Conformance or None
        The family's conformance matrix (:mod:`jvl_gym.registers.conformance`): for every
        register and documented bit, modelled, stored only or not modelled; None: none stated.
    statements : Statements or None
        The manual's statements about the family's registers, each with its status and tests
        (:mod:`jvl_gym.registers.statements`); None or empty: none stated.
    programs : module or None
        The stored-program module of a family that declares :attr:`Capability.PROGRAMS`:
        ``ProgramError`` (a malformed program), ``IoScriptError``, ``load_io_script`` (an I/O
        script of inputs, sensors and load over time), ``run_bench`` (a program run on a
        motor array with a script: the trace), ``write_csv`` and ``plot_trace``; the motor
        array then has ``store_program`` and ``program_status``. None otherwise.
    canopen : CanopenSpec or None
        The CANopen slave's facts of a family that declares :attr:`Capability.CANOPEN`, None
        otherwise.
    j1939_name : int or None
        The 64-bit NAME (SAE J1939/81, byte 0 lowest) with which the motors of a family that
        declares :attr:`Capability.J1939` claim their address; None otherwise.
    """

    key: str
    title: str
    compiled: ModuleType
    array_class: type
    table: RegisterTable
    constants: ModuleType
    units: ModuleType
    config: FamilyConfig
    task: ModuleType
    twin: TwinSpec
    capabilities: frozenset[Capability] = frozenset()
    tuning: TuningSpec | None = None
    conformance: Conformance | None = None
    statements: Statements | None = None
    programs: ModuleType | None = None
    canopen: CanopenSpec | None = None
    j1939_name: int | None = None

    @classmethod
    def of_package(cls, package: str, **fields: Any) -> Family:
        """The record of the family package ``package`` laid out as every family folder is:
        its ``compiled``, ``constants``, ``units``, ``config`` and ``task`` modules, the
        ``TABLE``, ``CONFORMANCE`` and ``STATEMENTS`` of its ``table`` module, and the plain
        facts of its ``family.yaml`` (key, title, capabilities, twin, J1939 NAME:
        :mod:`.record_file`); ``fields`` give the objects (array class, tuning, programs,
        …)."""
        import importlib

        from .record_file import record_fields

        modules = {name: importlib.import_module(f"{package}.{name}")
                   for name in ("compiled", "constants", "units", "config", "task", "table")}
        table = modules.pop("table")
        folder = Path(importlib.import_module(package).__file__ or "").parent
        facts = record_fields(folder, modules["constants"])
        return cls(**modules, table=table.TABLE,
                   conformance=getattr(table, "CONFORMANCE", None),
                   statements=getattr(table, "STATEMENTS", None), **facts, **fields)

    def motor_types(self) -> list[str]:
        """Names of the family's motor types (each with a motor config)."""
        return self.config.motor_types()

    def canonical_name(self, name: str) -> str:
        """The motor-type name a user's spelling stands for."""
        return self.config.canonical_motor_name(name)

    def load_motor(self, motor: Any) -> Any:
        """The validated motor config of ``motor`` (:meth:`FamilyConfig.load_motor`)."""
        return self.config.load_motor(motor)

    def supports(self, capability: Capability) -> bool:
        """Whether the family declares ``capability``."""
        return capability in self.capabilities

    def require(self, capability: Capability) -> None:
        """Nothing if the family declares ``capability``; :class:`UnsupportedOperation`
        naming it otherwise."""
        if capability not in self.capabilities:
            raise UnsupportedOperation(self.title, capability)

