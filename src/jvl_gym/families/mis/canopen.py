"""The CANopen slave of the MIS/SMC motors (MIS manual §11): its registers, bits, modes,
commands and identity as a :class:`~jvl_gym.families.contract.CanopenSpec` (``FAMILY.canopen``).

Registers are named as in the register table (MIS manual §8.2); the generic slave
(``jvl_gym.protocol.canopen``) looks them up by name.
"""

from __future__ import annotations

from pathlib import Path

from ..contract import CanopenSpec
from . import constants as c
from .units import COUNTS_PER_REV

__all__ = ["CANOPEN", "EDS", "SETUP_USE_BECKHOFF"]

#: SETUP_BITS bit 14 "UseBeckhoff" (§8.2.68, §11.4.11)
SETUP_USE_BECKHOFF = 1 << 14
#: the EDS file of the served object dictionary (§11.4; generated from it)
EDS = Path(__file__).with_name("mis.eds")

CANOPEN = CanopenSpec(
    # node id (1 … 127, default 5) and bit-rate code (§11.2.4, §8.2.98–99)
    node_id="FBUS_NODE_ID", baud="FBUS_BAUD",
    # MODE_REG and the profile registers (§8.2.3–8.2.19, D_SOLL §8.2.1)
    mode="MODE_REG", p_soll="P_SOLL", v_soll="V_SOLL", a_soll="A_SOLL", d_soll="D_SOLL",
    p_ist="P_IST", v_ist="V_IST", flwerr="FLWERR", flwerrmax="FLWERRMAX",
    # error bits (§8.2.31), status bits (§8.2.24), COMMAND (§8.2.20), I/O (§8.2.16–17),
    # SETUP_BITS (§8.2.68)
    err_bits="ERR_BITS", statusbits="STATUSBITS", command="COMMAND", inputs="INPUTS",
    outputs="OUTPUTS", setup_bits="SETUP_BITS",
    # running current (§8.2.7), zero search (§8.2.34–37, §8.2.72–74, §8.2.125)
    run_current="RUN_CURRENT", home_mask="HOME_MASK", nl_mask="NL_MASK", pl_mask="PL_MASK",
    v_home="V_HOME", v_home_crawl="V_HOME_CRAWL", p_home="P_HOME", t_home="T_HOME",
    # identity (§8.2.89–92, §8.2.2)
    motor_type="MOTORTYPE", serial="SERIAL_NUMBER", version="PROG_VERSION",
    hardware="HARDWARE_REV",
    # MODE_REG values (§8.2.3)
    passive=c.PASSIVE, velocity=c.VELOCITY, position=c.POSITION,
    zero_search_1=c.ZERO_SEARCH_1, zero_search_2=c.ZERO_SEARCH_2,
    # STATUSBITS (§8.2.24) and ERR_BITS (§8.2.31) masks
    st_in_position=c.ST_IN_POSITION, st_at_velocity=c.ST_AT_VELOCITY,
    st_zero_search_done=c.ST_ZERO_SEARCH_DONE,
    err_general=c.ERR_GENERAL, err_follow=c.ERR_FOLLOW, err_low_bus=c.ERR_LOW_BUS,
    err_position=c.ERR_POSITION_LIMIT, err_zero_search_timeout=c.ERR_ZERO_SEARCH_TIMEOUT,
    # clear errors (97, §8.2.21); save to flash and continue (269, §8.2.22; passive only)
    cmd_clear_errors=c.CMD_CLEAR_ERRORS, cmd_save=c.CMD_SAVE,
    beckhoff_bit=SETUP_USE_BECKHOFF,
    # object 608Fh: 409 600 counts per revolution (§8.2.4)
    counts_per_rev=COUNTS_PER_REV,
    # JVL's vendor id 0x117, device type 0x40192, 1008h "JVL A/S" (§11.4.1); 6402h "MIS"
    vendor_id=0x117, device_type=0x40192, device_name="JVL A/S", motor_name="MIS",
    product_name="MIS/SMC integrated step motor (simulated)", eds=EDS,
    # ZERO_SEARCH_BITS and its bits 0, 1, 2, 4, 5 (§8.2.67): the DSP-402 homing methods
    zero_search_bits="ZERO_SEARCH_BITS", zs_use_index=c.ZS_USE_INDEX,
    zs_turn_at_limit=c.ZS_TURN_AT_LIMIT, zs_opposite_side=c.ZS_OPPOSITE_SIDE,
    zs_ignore_switch=c.ZS_IGNORE_SWITCH, zs_no_time_out=c.ZS_NO_TIME_OUT)
