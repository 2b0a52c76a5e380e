"""What a motor family may support (:class:`Capability`), and the error of an operation a
family lacks (:class:`UnsupportedOperation`): part of the family contract (:mod:`.contract`)."""

from __future__ import annotations

import enum

__all__ = ["Capability", "UnsupportedOperation", "motors_of"]


class Capability(enum.Enum):
    """What a family may support, declared in :attr:`Family.capabilities`.

    The operations (the first group) are methods of :class:`~jvl_gym.MotorArray`; the others
    are firmware features that tasks and tuning ask for.
    """

    #: ``enter_safe_mode`` / ``exit_safe_mode``: the bridge off, flash and reset allowed
    #: (MAC050–141 manual 4.4.16, MIS manual §8.2.3)
    SAFE_MODE = "safe mode"
    #: ``go_init_mode``: the MacTalk "go init mode" path to INIT_MODE (MAC050–141 manual 5.1)
    INIT_MODE = "init mode"
    #: ``software_reset``: the firmware restarts from flash, the rotor keeps moving
    SOFTWARE_RESET = "software reset"
    #: ``write_flash``: save the register set in flash (in safe mode), then restart from it
    FLASH = "flash save"
    #: ``sample_buffer`` / ``sample_buffer_raw``: the registers SAMPLE1 … SAMPLE4 recorded
    SAMPLE_BUFFER = "sample buffer"
    #: ``torque``: the electromagnetic torque of the plant
    TORQUE = "torque observable"
    #: ``energy``: the energy accounts of the plant
    ENERGY = "energy accounts"
    #: the TESTU/TESTA test modes (MAC050–141 manual 4.4.9, 4.4.10)
    TEST_MODES = "TESTU/TESTA test modes"
    #: FastMAC/FlexMAC on the user interface (``interface_bits``; MAC050–141 manual 5.2)
    USER_INTERFACE = "FastMAC/FlexMAC user interface"
    #: an analogue torque mode (MAC050–141 manual 4.4.4; MAC800 mode 4)
    ANALOG_TORQUE = "analogue torque mode"
    #: an analogue gear mode (MAC050–141 manual 4.4.7; MAC800 mode 18)
    ANALOG_GEAR = "analogue gear mode"
    #: a speed-loop filter of registers to design (MAC050–141 manual 3.2.89–3.2.111)
    SPEED_FILTER = "speed-loop filter"
    #: a COIL mode with the registers that drive it (MAC050–141 manual 4.4.13)
    COIL_MODE = "COIL mode"
    #: a step motor's microstep indexing (MIS manual §8.2)
    STEP_INDEXING = "step-motor indexing"
    #: stored programs run by the firmware (MIS manual chapter 9): :attr:`Family.programs`
    PROGRAMS = "stored programs"
    #: a CANopen slave, CiA DS-301/DSP-402 (MIS manual §11): :attr:`Family.canopen`
    CANOPEN = "CANopen interface"
    #: DMX512 reception on the RS485 line (MIS manual §13)
    DMX512 = "DMX512 interface"
    #: an SAE J1939 node on the CAN bus (MIS manual §11.8)
    J1939 = "SAE J1939 interface"


def motors_of(family_title: str) -> str:
    """The motors of a family in words: its title where the title names them ("MAC800
    integrated servo motors"), else the title followed by "motors"."""
    return family_title if family_title.endswith("motors") else f"{family_title} motors"


class UnsupportedOperation(NotImplementedError):
    """An operation the motors' family does not support; nothing was changed.

    Parameters
    ----------
    family_title : str
        The family's human name.
    capability : Capability
        What the operation needs.
    """

    def __init__(self, family_title: str, capability: Capability) -> None:
        self.capability = capability
        super().__init__(f"{motors_of(family_title)} have no {capability.value} "
                         f"(the family does not declare Capability.{capability.name})")
