"""``jvl-gym serve``: the digital twin on a pseudo-terminal and/or TCP on localhost.

Motors of several families may share the line, each answering in its family's MacTalk dialect
(``protocol.mactalk.line``); ``--modbus`` serves motors of one 32-bit family (MIS) over Modbus
RTU instead (MIS manual §12).

Examples
--------
``jvl-gym serve --motor MAC140 --address 19 --tcp 127.0.0.1:5000``
``jvl-gym serve --motor MAC140 --address 19 --address 20 --pty --speed 4``
``jvl-gym serve -m MAC140 -a 19 -m MIS231 -a 7 --pty``  (two families, one line)
``jvl-gym serve --motor MIS231 --address 42 --modbus --tcp 127.0.0.1:5020``
``python -m jvl_gym.cli.serve --motor MAC050 --pty --user-pty``  (FastMAC/FlexMAC too)
``jvl-gym serve -m MIS232 -a 1 -m MIS232 -a 2 --canopen --can-interface socketcan
--can-channel vcan0 --node-id 5 --node-id 6``  (two MIS as CANopen slaves, MIS manual §11)
``jvl-gym serve -m MIS232 --canopen --can-interface udp_multicast``  (a CANopen slave that a
master in another process of this host reaches on python-can's ``udp_multicast``, group
239.74.163.2, loopback only)
``jvl-gym serve -m MIS232 --j1939 udp_multicast:239.74.163.2``  (a J1939 node, the same way)
``jvl-gym serve -m MAC140 -a 19 --tcp 127.0.0.1:5000 --load-inertia 1e-4``  (a rigid load)
``jvl-gym serve -m MAC140 -a 19 --pty --load-inertia 1e-4 --coupling-stiffness 40``
(the load behind an elastic coupling: a two-mass plant)

The load options (:data:`LOAD_OPTIONS`) set the motors' reset keywords of those names
(:class:`~jvl_gym.MotorArray`; docs/model.md §5.2 "Mechanics"): given once for every motor or
once per ``--address``, in SI units, checked by the motor array (finite, >= 0; an elastic
coupling the inner step can carry). The elastic coupling is the MAC050–141's alone; on a
family without it a value other than 0 is refused.
"""

from __future__ import annotations

import logging
import re
import signal
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from ..protocol.serving.realtime import heap_frozen
from ..registers.errors import echo
from .app import App

__all__ = ["app", "serve", "parse_tcp", "banner", "build_line", "LOAD_OPTIONS",
           "LoadError", "load_per_motor", "canopen_server"]

app = App(prog="jvl-gym serve", add_completion=False,
          help="Serve simulated MAC motors over serial protocols.")


def banner(types: list[str], twin: Any, given: list[int] | None = None) -> list[str]:
    """One line per motor: its type and the address it answers at (MYADDR now, which a flash
    file may have set; ``given`` are the ``--address`` values, named when they differ)."""
    lines = []
    for i, (t, a) in enumerate(zip(types, twin.addresses())):
        note = ""
        if given is not None and given[i] != a:
            note = f" (from the flash file; --address said {given[i]})"
        lines.append(f"motor {i}: {t} at address {a}{note}")
    return lines


def parse_tcp(text: str) -> tuple[str, int]:
    """``"127.0.0.1:5000"`` or ``"5000"`` → (host, port); only local hosts are allowed."""
    from ..protocol.serving.transport import LOCALHOSTS

    host, _, port = text.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    if host not in LOCALHOSTS:
        raise typer.BadParameter(f"TCP is served on localhost only, not {echo(host)}")
    if not port.isdigit() or not 0 <= int(port) <= 65535:
        raise typer.BadParameter(f"bad TCP port in {echo(text)}")
    return host, int(port)


class LoadError(ValueError):
    """A load option the motors refuse (one line, naming the option)."""


#: the load options of ``serve`` → the ``MotorArray`` reset keywords they set (SI units:
#: kg·m², N·m, N·m·s/rad, N·m/rad, N·m·s/rad; docs/model.md §5.2)
LOAD_OPTIONS: dict[str, str] = {
    "--load-inertia": "load_inertia",
    "--coulomb-friction": "coulomb_friction",
    "--viscous-friction": "viscous_friction",
    "--coupling-stiffness": "coupling_stiffness",
    "--coupling-damping": "coupling_damping",
}


def _option_text(text: str) -> str:
    """``text`` with the load's reset keywords named by their ``serve`` options."""
    for option, keyword in LOAD_OPTIONS.items():
        text = text.replace(keyword, option)
    return text


def load_per_motor(given: dict[str, Sequence[float] | None], addresses: Sequence[int]
                   ) -> dict[str, list[float]]:
    """The load of each motor (one per ``addresses``): reset keyword → one value per motor,
    from the values of the load options ``given`` (option of :data:`LOAD_OPTIONS` → one
    value for every motor, one per motor, or None: not given).

    Raises
    ------
    LoadError
        An option given neither once nor once per address, or a coupling damping on a motor
        without a coupling stiffness (one line, naming the option). The values themselves are
        the motor array's to check (:func:`build_line`).
    """
    n = len(addresses)
    load: dict[str, list[float]] = {}
    for option, values in given.items():
        if not values:
            continue
        if len(values) not in (1, n):
            raise LoadError(f"{option}: give one value for every motor or one per --address "
                            f"({n}), got {len(values)}")
        load[LOAD_OPTIONS[option]] = [float(v) for v in values] * (n // len(values))
    damping = load.get("coupling_damping", [0.0] * n)
    stiffness = load.get("coupling_stiffness", [0.0] * n)
    for a, d, k in zip(addresses, damping, stiffness):
        if d != 0.0 and not k > 0.0:
            raise LoadError(f"--coupling-damping {d:g} for the motor at address {a} needs a "
                            "--coupling-stiffness > 0 there (the damping is the coupling's)")
    return load


def _put_load(twin: Any, load: dict[str, list[float]], members: list[int]) -> None:
    """Power on the motors of ``twin`` (the line's motors ``members``) with their ``load``
    (:meth:`~jvl_gym.MotorArray.reset`: registers from flash, so the addresses stay); one-line
    :class:`LoadError` naming the option and the address for a value the family refuses, nothing
    changed."""
    from ..families import families, family

    m = twin.m
    kw = {}
    for keyword, values in load.items():
        mine = [values[k] for k in members]
        if keyword in m.PARAMETER_KEYWORDS:
            kw[keyword] = mine
        elif any(v != 0.0 for v in mine):
            option = next(o for o, k in LOAD_OPTIONS.items() if k == keyword)
            types = sorted({cfg.name for cfg in m.motor_configs})
            having = [family(key).title for key in families()
                      if keyword in family(key).array_class.PARAMETER_KEYWORDS]
            raise LoadError(f"{option}: the {m.family.title} ({', '.join(types)}) model no "
                            f"{keyword.replace('_', ' ')} (only the {', '.join(having)} do); "
                            "give 0 for them")
    if not kw:
        return
    try:
        m.reset(**kw)
    except (TypeError, ValueError) as exc:
        text = re.sub(r"^motor (\d+):",
                      lambda g: f"motor at address {twin.addresses()[int(g[1])]}:", str(exc))
        raise LoadError(_option_text(text)) from None


def build_line(types: list[str], addresses: list[int], seed: int = 0,
               flash_dir: Path | None = None,
               fastmac_code: dict[str, tuple[int, int]] | None = None,
               load: dict[str, list[float]] | None = None, line_env: str | None = None,
               **array_kw: Any) -> tuple[Any, list[int]]:
    """The twins of ``types`` at ``addresses``: one :class:`~..protocol.mactalk.twin16.Twin` per
    motor family (a :class:`~..protocol.mactalk.line.Bus` of them when there are several), and
    the motor indices in the order the line lists them (family by family). With several families
    each keeps its flash files in ``flash_dir/<family key>``; ``array_kw`` go to every
    ``MotorArray``; ``load`` (reset keyword → one value per motor of ``types``,
    :func:`load_per_motor`) is each motor's load after power-on. ``line_env`` serves one motor
    inside the machine of that env instead (``jvl_gym.rl.lines``: GearSync's web line), its
    lines drawn from ``seed``.

    Raises
    ------
    LoadError
        A load value the motor's family refuses (one line, naming the option).
    """
    from ..families import family_of_motor
    from ..motor.array import MotorArray
    from ..protocol.mactalk import fastmac as fm
    from ..protocol.mactalk.line import Bus
    from ..protocol.mactalk.twin16 import Twin

    groups: dict[str, list[int]] = {}
    for k, t in enumerate(types):
        groups.setdefault(family_of_motor(t).key, []).append(k)
    twins: list[Twin] = []
    try:
        for key, members in groups.items():
            if line_env is not None:
                from ..rl.lines import make_line

                if len(types) != 1 or array_kw or load:
                    raise ValueError("--line serves one motor, without load options")
                m = make_line(line_env, types[0], seed)
            else:
                m = MotorArray([types[k] for k in members], n=len(members), seed=seed,
                               **array_kw)
            where = flash_dir / key if flash_dir is not None and len(groups) > 1 else flash_dir
            twin = Twin(m, [addresses[k] for k in members], flash_dir=where,
                        fastmac_code=fastmac_code or fm.DEFAULT_CODE)
            twins.append(twin)
            _put_load(twin, load or {}, members)
    except BaseException:
        for twin in twins:  # their flash directories are free again
            twin.close()
        raise
    order = [k for members in groups.values() for k in members]
    return (twins[0] if len(twins) == 1 else Bus(twins)), order


@app.command()
def serve(
    motor: Annotated[list[str] | None, typer.Option(
        "--motor", "-m", help="Motor type (repeat: one per --address; default MAC140).")] = None,
    address: Annotated[list[int] | None, typer.Option(
        "--address", "-a", help="MYADDR 1..254 of each motor (repeat: multi-drop; default 1).")
    ] = None,
    tcp: Annotated[str | None, typer.Option(
        help="MacTalk (or Modbus RTU) over TCP, HOST:PORT on localhost (port 0: any free port)."
    )] = None,
    pty: Annotated[bool, typer.Option(
        "--pty", help="MacTalk (or Modbus RTU) over a pseudo-terminal.")] = False,
    modbus: Annotated[bool, typer.Option(
        "--modbus", help="Serve Modbus RTU (MIS manual §12) instead of MacTalk: motors of one "
        "32-bit family (MIS) at addresses 1..247.")] = False,
    modbus_switch: Annotated[bool, typer.Option(
        "--modbus-switch", help="Serve the MIS main channel as the motor does: MacTalk after "
        "power-on, Modbus RTU after 1 s of silence if bit 0 of register 121 is set (MIS manual "
        "§12.2.1).")] = False,
    dmx: Annotated[bool, typer.Option(
        "--dmx", help="Serve DMX512 (MIS manual §13) instead of MacTalk: break FFh 00h 00h, "
        "FFh sent as FFh FFh (docs/protocol.md).")] = False,
    dmx_start: Annotated[list[int] | None, typer.Option(
        "--dmx-start", help="DMX Start Address 1 of each motor (repeat, one per --address; "
        "default 1, 4, 7, …); Start Address 2 is 500.")] = None,
    j1939: Annotated[str | None, typer.Option(
        "--j1939", help="Also serve the motors as J1939 nodes (MIS manual §11.8) on a "
        "python-can bus INTERFACE:CHANNEL, e.g. socketcan:vcan0, udp_multicast:239.74.163.2 "
        "(other processes of this host) or virtual:bus0 (this process).")] = None,
    j1939_address: Annotated[list[int] | None, typer.Option(
        "--j1939-address", help="J1939 node address 1..252 of each motor (repeat; default "
        "the motor's FBUS_NODE_ID, 5).")] = None,
    user_tcp: Annotated[int | None, typer.Option(
        help="FastMAC/FlexMAC user interface of motor i on TCP port BASE+i (0: free ports).")
    ] = None,
    user_pty: Annotated[bool, typer.Option(
        "--user-pty", help="FastMAC/FlexMAC user interfaces on pseudo-terminals.")] = False,
    speed: Annotated[float, typer.Option(help="Simulated seconds per wall-clock second.")] = 1.0,
    seed: Annotated[int, typer.Option(help="Noise seed.")] = 0,
    flash_dir: Annotated[Path | None, typer.Option(
        help="Directory of the flash files (persist 'write to flash' across runs).")] = None,
    record_length: Annotated[int | None, typer.Option(
        help="TESTU/TESTA record length of the MAC050–141 (manual: 11).", min=1)] = None,
    fastmac_code: Annotated[str, typer.Option(
        help="FastMAC register code: 'example' (manual 5.2.1.5) or 'table' (5.2.1.4).")
    ] = "example",
    load_inertia: Annotated[list[float] | None, typer.Option(
        "--load-inertia", help="Load inertia at the shaft in kg·m², >= 0 (repeat: one per "
        "--address; once: every motor). Default: none, the bare rotor.")] = None,
    coulomb_friction: Annotated[list[float] | None, typer.Option(
        "--coulomb-friction", help="Coulomb friction torque in N·m, >= 0 (repeat like "
        "--load-inertia). Default: the motor type's.")] = None,
    viscous_friction: Annotated[list[float] | None, typer.Option(
        "--viscous-friction", help="Viscous friction in N·m·s/rad, >= 0 (repeat like "
        "--load-inertia). Default: the motor type's.")] = None,
    coupling_stiffness: Annotated[list[float] | None, typer.Option(
        "--coupling-stiffness", help="Stiffness in N·m/rad of an elastic coupling the load "
        "sits behind (a two-mass plant; needs --load-inertia > 0; MAC050–141 only; 0: rigid; "
        "repeat like --load-inertia).")] = None,
    coupling_damping: Annotated[list[float] | None, typer.Option(
        "--coupling-damping", help="Damping of that coupling in N·m·s/rad (needs "
        "--coupling-stiffness > 0; repeat like --load-inertia).")] = None,
    canopen: Annotated[bool, typer.Option(
        "--canopen", help="Serve the motors as CANopen slaves (MIS manual §11) on a python-can "
        "bus, beside any --tcp/--pty endpoint of the same motors.")] = False,
    can_interface: Annotated[str, typer.Option(
        help="python-can interface of --canopen (socketcan, udp_multicast: other processes "
        "of this host, virtual: this process only, pcan, …).")
    ] = "socketcan",
    can_channel: Annotated[str | None, typer.Option(
        help="python-can channel of --canopen (vcan0, can0, a multicast group of "
        "udp_multicast, a virtual bus name, …; default vcan0, for udp_multicast "
        "239.74.163.2).")
    ] = None,
    can_bitrate: Annotated[int | None, typer.Option(
        help="Bit rate [bit/s] of --canopen, for interfaces that set it.")] = None,
    node_id: Annotated[list[int] | None, typer.Option(
        "--node-id", help="CANopen node id 1..127 of each motor (repeat: one per --address; "
        "default: each motor's register 166, factory value 5).")] = None,
    max_connections: Annotated[int, typer.Option(
        help="Connections each TCP endpoint serves at once; one more is closed at once.",
        min=1)] = 32,
    idle_timeout: Annotated[float, typer.Option(
        help="Seconds without a received byte after which a TCP connection is closed (0: "
        "never).", min=0.0)] = 300.0,
    line_env: Annotated[str | None, typer.Option(
        "--line", help="Serve the one motor inside an env's machine: jvl_gym/GearSync-v0 (its "
        "web line: the master encoder on the pulse input, the load cell on the analogue "
        "input, 0..10 V for 0..100 N; lines drawn from --seed).")] = None,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log every refusal.")] = False,
) -> None:
    """Serve one or many simulated motors (multi-drop by MYADDR) until Ctrl-C, each with
    an optional load: inertia, friction, an elastic coupling (SI units; one value for every
    motor or one per --address; checked before anything is served)."""
    from ..protocol.mactalk import fastmac as fm
    from ..protocol.serving.canbus import DEFAULT_GROUP, UDP_MULTICAST
    from ..protocol.serving.transport import TwinServer
    from ..protocol.serving.twin import FlashDirectoryInUse

    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING)
    motor = motor or ["MAC140"]
    address = address or [1]
    if tcp is None and not pty and not canopen and j1939 is None:
        raise typer.BadParameter("give --tcp HOST:PORT, --pty, --canopen and/or --j1939")
    if node_id and not canopen:
        raise typer.BadParameter("--node-id is the CANopen node id: give --canopen too")
    if node_id and len(node_id) != len(address):
        raise typer.BadParameter(f"give one --node-id per --address ({len(address)}), got "
                                 f"{len(node_id)}")
    if dmx and canopen:
        raise typer.BadParameter("--dmx serves the DMX line only (no --canopen)")
    types = motor if len(motor) == len(address) else [motor[0]] * len(address)
    if len(motor) not in (1, len(address)):
        raise typer.BadParameter("give one --motor, or one per --address")
    _check_distinct(address, types, "--address")
    if user_tcp is not None and user_tcp != 0 and not 1 <= user_tcp <= 65536 - len(address):
        raise typer.BadParameter(
            f"{user_tcp}: motor i listens on port {user_tcp}+i, so give a base port in "
            f"1..{65536 - len(address)} for {len(address)} motor(s) (TCP ports are 1..65535), "
            "or 0 for free ports", param_hint="'--user-tcp'")
    code = {"example": fm.EXAMPLE_CODE, "table": fm.TABLE_CODE}.get(fastmac_code)
    if code is None:
        raise typer.BadParameter("--fastmac-code is 'example' or 'table'")
    modbus = modbus or modbus_switch
    if modbus and (user_tcp is not None or user_pty):
        raise typer.BadParameter("--modbus serves the main channel only (no --user-tcp/-pty)")
    array_kw = {} if record_length is None else {"record_length": record_length}
    given = dict(zip(LOAD_OPTIONS, (load_inertia, coulomb_friction, viscous_friction,
                                    coupling_stiffness, coupling_damping)))
    try:
        load = load_per_motor(given, address)
        line, order = build_line(types, list(address), seed=seed, flash_dir=flash_dir,
                                 fastmac_code=code, load=load, line_env=line_env, **array_kw)
    except LoadError as exc:
        raise typer.BadParameter(str(exc)) from None
    except FlashDirectoryInUse as exc:
        raise typer.BadParameter(str(exc), param_hint="'--flash-dir'") from None
    except (TypeError, ValueError) as exc:  # the arrays' own check of the record length
        if line_env is not None:
            raise typer.BadParameter(str(exc), param_hint="'--line'") from None
        if record_length is None or not any(w in str(exc) for w in ("record_length",
                                                                    "record length")):
            raise
        kinds = ", ".join(dict.fromkeys(types))
        raise typer.BadParameter(f"{record_length} refused for {kinds}: {exc}",
                                 param_hint="'--record-length'") from None
    _check_distinct(line.addresses(), [types[k] for k in order], "--flash-dir")
    endpoint = parse_tcp(tcp) if tcp else None
    can_server = None
    if can_channel is None:
        can_channel = DEFAULT_GROUP if can_interface == UDP_MULTICAST else "vcan0"
    if canopen:
        ids = None if not node_id else [node_id[k] for k in order]
        can_server = canopen_server(line, can_interface, can_channel, ids, speed,
                                    bitrate=can_bitrate)
    clock = can_server is None
    limits = {"max_connections": max_connections, "idle_timeout": idle_timeout}
    # the motors' compiled step is ready (compiled, or loaded from the compile cache) before
    # anything listens: a client's first request is not kept waiting for it under the lock
    line.warm_up()
    try:
        if can_server is not None and tcp is None and not pty:
            server: Any = None
        elif dmx:
            server = _dmx_server(line, endpoint, pty, speed, dmx_start,
                                 modbus or user_tcp is not None or user_pty, limits)
        elif modbus:
            server = _modbus_server(line, endpoint, pty, speed, switch=modbus_switch,
                                    run_clock=clock, limits=limits)
        else:
            server = TwinServer(line, speed=speed, tcp=endpoint, pty=pty, user_tcp=user_tcp,
                                user_pty=user_pty, run_clock=clock, **limits)
        node = _j1939_node(line, j1939, j1939_address) if j1939 is not None else None
    except typer.BadParameter:
        if can_server is not None:
            can_server.stop()
        raise
    if server is not None:
        try:
            server.start()
        except OSError as exc:
            server.stop()
            if can_server is not None:
                can_server.stop()
            raise typer.BadParameter(exc.strerror or str(exc), param_hint="'--tcp'") from None
    if can_server is not None:
        can_server.start()
    done = threading.Event()
    # before the ready line: a Ctrl-C or SIGTERM right after it stops serve cleanly
    previous = {sig: signal.signal(sig, lambda *_: done.set())
                for sig in (signal.SIGINT, signal.SIGTERM)}
    # the heap frozen before the ready line: the one full collection comes before any client,
    # and none of the loaded code stalls the clock after it (protocol.serving.realtime)
    frozen = heap_frozen()
    frozen.__enter__()
    try:
        for text in banner([types[k] for k in order], line, [address[k] for k in order]):
            typer.echo(text)
        for e in server.endpoints if server is not None else []:
            typer.echo(f"{e.what} {e.kind}: {e.url}", err=False)
        if can_server is not None:
            for k, s in enumerate(can_server.slaves):
                typer.echo(f"canopen {can_interface}:{can_channel}: motor {k} node id "
                           f"{s.node_id}")
        typer.echo(f"running at speed {speed}; Ctrl-C to stop")
        done.wait()
    finally:
        frozen.__exit__(None, None, None)
        if can_server is not None:
            can_server.stop()
        if server is not None:
            server.stop()
        if node is not None:
            node.close()
            node.bus.shutdown()
        line.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        stats = server.bus.stats if modbus and server is not None else line.stats
        typer.echo(f"stopped; {dict(stats)}")


def _check_distinct(addresses: Sequence[int], types: Sequence[str], option: str) -> None:
    """Nothing if every motor has an address of its own; a one-line BadParameter naming the
    address, the two motors and ``option`` (where the addresses come from) otherwise: two
    motors at one address would both answer the requests to it."""
    seen: dict[int, int] = {}
    for k, a in enumerate(addresses):
        if a in seen:
            j = seen[a]
            verb = "get from the flash files" if option == "--flash-dir" else "are given"
            raise typer.BadParameter(
                f"motor {j} ({types[j]}) and motor {k} ({types[k]}) {verb} the same "
                f"address {a}; give every motor its own address", param_hint=f"'{option}'")
        seen[a] = k


def canopen_server(line: Any, interface: str, channel: str, node_ids: list[int] | None,
                   speed: float, bitrate: int | None = None, run_clock: bool = True) -> Any:
    """A CANopen server (:class:`~.protocol.canopen.server.CanopenServer`) of the motors of
    ``line`` (a twin or a bus of twins, every one of a family with a CANopen interface) on the
    python-can bus ``interface``/``channel``; one-line BadParameter for a family without
    CANopen, a bad node id or a bus that cannot be opened (nothing left open)."""
    from ..families import Capability
    from ..protocol.canopen.server import CanopenServer, open_bus

    twins = list(getattr(line, "twins", [line]))
    _require(twins, Capability.CANOPEN, "--canopen")
    try:
        bus = open_bus(interface, channel, bitrate)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    try:
        return CanopenServer(twins, bus, node_ids=node_ids, speed=speed, run_clock=run_clock)
    except ValueError as exc:
        bus.shutdown()
        raise typer.BadParameter(f"--canopen: {exc}") from None


def _require(twins: list[Any], capability: Any, option: str) -> None:
    """Nothing if every twin's family declares ``capability``; a one-line BadParameter naming
    it and the motor types of the families that have it otherwise."""
    from ..families import UnsupportedOperation, families_with

    for twin in twins:
        try:
            twin.m.family.require(capability)
        except UnsupportedOperation as exc:
            types = ", ".join(t for fam in families_with(capability) for t in fam.motor_types())
            raise typer.BadParameter(f"{option}: {exc}; serve motors that have it ({types})"
                                     ) from None


def _j1939_node(line: Any, spec: str, addresses: list[int] | None) -> Any:
    """J1939 nodes of the motors of ``line`` on the python-can bus ``spec`` (INTERFACE:CHANNEL),
    claiming their addresses now."""
    from ..families import Capability
    from ..protocol.mactalk.twin16 import Twin
    from ..protocol.sae_j1939.node import J1939Node
    from ..protocol.serving.canbus import open_bus as open_can_bus

    _require(list(getattr(line, "twins", [line])), Capability.J1939, "--j1939")
    if not isinstance(line, Twin):
        raise typer.BadParameter("--j1939 serves motors of one family")
    interface, sep, channel = spec.partition(":")
    if not sep or not interface or not channel:
        raise typer.BadParameter(f"--j1939 {echo(spec)}: give INTERFACE:CHANNEL, e.g. "
                                 "socketcan:vcan0")
    given = addresses is not None
    if addresses is None:
        addresses = [int(v) for v in line.m.read_raw("FBUS_NODE_ID")]
    try:
        J1939Node.check_addresses(addresses, line.m.n)
    except ValueError as exc:
        where = "" if given else " (by default each motor's FBUS_NODE_ID)"
        raise typer.BadParameter(f"{exc}{where}", param_hint="'--j1939-address'") from None
    try:
        bus = open_can_bus(interface, channel)
    except ValueError as exc:
        raise typer.BadParameter(f"--j1939 {spec}: {exc}") from None
    try:
        node = J1939Node(line, bus, addresses)
    except ValueError as exc:
        bus.shutdown()
        raise typer.BadParameter(f"--j1939-address: {exc}") from None
    typer.echo(f"j1939 {spec}: node addresses {', '.join(str(a) for a in addresses)}")
    return node.start()


def _dmx_server(line: Any, tcp: tuple[str, int] | None, pty: bool, speed: float,
                starts: list[int] | None, other: bool,
                limits: dict[str, Any] | None = None) -> Any:
    """A DMX512 server of the motors of ``line`` (one twin of a family with DMX512);
    ``limits`` are the TCP endpoint's (``max_connections``, ``idle_timeout``)."""
    from ..families import Capability
    from ..protocol.dmx512.receiver import DmxSettings
    from ..protocol.dmx512.server import DmxLine, DmxServer
    from ..protocol.mactalk.twin16 import Twin

    if other:
        raise typer.BadParameter("--dmx serves the DMX line only (no --modbus, --user-tcp/-pty)")
    _require(list(getattr(line, "twins", [line])), Capability.DMX512, "--dmx")
    if not isinstance(line, Twin):
        raise typer.BadParameter("--dmx serves motors of one family")
    n = line.m.n
    starts = starts or [1 + 3 * i for i in range(n)]
    if len(starts) != n:
        raise typer.BadParameter(f"give one --dmx-start per --address ({n})")
    try:
        settings = [DmxSettings(start_address1=a) for a in starts]
        return DmxServer(line, speed=speed, tcp=tcp, pty=pty, line=DmxLine(line, settings),
                         **(limits or {}))
    except (ValueError, KeyError) as exc:
        raise typer.BadParameter(f"--dmx: {exc}") from None


def _modbus_server(line: Any, tcp: tuple[str, int] | None, pty: bool, speed: float,
                   switch: bool = False, run_clock: bool = True,
                   limits: dict[str, Any] | None = None) -> Any:
    """A Modbus RTU server of the motors of ``line`` (one twin of a 32-bit family); with
    ``switch``, every stream starts in MacTalk and goes to Modbus as the first motor's register
    121 says (MIS manual §12.2.1), the silence counted from now (power-on); ``limits`` are the
    TCP endpoint's (``max_connections``, ``idle_timeout``)."""
    import time

    from ..protocol.mactalk.twin16 import Twin
    from ..protocol.modbus.server import (
        ModbusServer,
        ModbusSession,
        ProtocolSwitch,
        SwitchingSession,
    )
    from ..protocol.modbus.twin import modbus_bus

    if not isinstance(line, Twin):
        raise typer.BadParameter("--modbus serves motors of one family")
    try:
        bus = modbus_bus(line)
    except ValueError as exc:
        raise typer.BadParameter(f"--modbus: {exc}") from None
    for a in line.addresses():
        if not 1 <= a <= 247:
            raise typer.BadParameter(f"--modbus: address {a} is no Modbus slave address "
                                     "(1..247; MIS manual §12.1)")
    if not switch:
        return ModbusServer(line, speed=speed, tcp=tcp, pty=pty, bus=bus, run_clock=run_clock,
                            **(limits or {}))
    setup = bus.slaves[0].registers.setup
    if setup is None:
        raise typer.BadParameter("--modbus-switch: the family has no Modbus set-up register")
    line_switch = ProtocolSwitch.for_device(bus.slaves[0].device, setup, time.monotonic())

    def switching() -> SwitchingSession:
        return SwitchingSession(line.session(), ModbusSession(bus), line_switch)

    return ModbusServer(line, speed=speed, tcp=tcp, pty=pty, bus=bus, run_clock=run_clock,
                        make_session=switching, **(limits or {}))


if __name__ == "__main__":
    app()
