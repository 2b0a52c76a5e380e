"""``jvl-gym studio``: the motor workbench in the browser (docs/studio.md).

The logic lives in modules of one concept each and runs without a browser:

* :mod:`.facts` — what the studio takes from a motor family (register table, mode names,
  error and status bits, test modes), through the family's public objects only;
* :mod:`.motor` — one motor seen by the studio: :class:`~.motor.SimMotor` (one in-process
  :class:`~jvl_gym.MotorArray`), :mod:`.line` — :class:`~.line.LineMotor` (a twin or a real
  motor behind the project's MacTalk clients, either dialect), :mod:`.session` — the motors
  of a studio and the real-time clock of the simulated ones; :mod:`.connections` — lines
  connected, scanned and closed, motors identified, added and removed while the studio runs;
* :mod:`.bits` — bit registers in words, :mod:`.groups` — the register groups of the manuals,
  :mod:`.registers` — the register view's rows, edits and setup files;
* :mod:`.units_view` — register values in engineering units, mode registers as mode names,
  bit registers as named bits; :mod:`.motion` — the motion panel (enable, jog, run, moves,
  home) on each family's modes; :mod:`.parameters` — the settings against flash, defaults or
  a setup file, undo and redo, the flash write;
* :mod:`.scope` — scope channels and buffers, CSV and PNG export; :mod:`.trigger` — trigger,
  time base, cursors, trace scaling and recording; :mod:`.capture` — the motor's sample buffer
  and the TESTU/TESTA records; :mod:`.compiling` — the compile notice;
* :mod:`.tuning_run` — the ``jvl-tune`` pipeline as steps with progress, through the tuning
  toolkit the studio is given (:mod:`.toolkit`);
* :mod:`.episodes` — one episode of a registered env with its policy or baseline;
* :mod:`.lock` — who may reach the studio: the Host and Origin rules and the token of each
  start, an ASGI middleware in front of the pages and the websocket.

STOP (:meth:`.session.Session.stop_motors`) stops every motor by its family's stop
(:attr:`~jvl_gym.families.TwinSpec.stop_mode`).

The browser pages (:mod:`.ui`, NiceGUI) only lay these out.
"""
