"""The command line: ``jvl-gym`` and its command groups.

:mod:`.main` is the app (the ``jvl-gym`` entry point) with the env, training and scale commands;
:mod:`.app` the typer app class and the one-line error handling every command shares;
:mod:`.serve` ``jvl-gym serve`` (twins on every bus), :mod:`.studio` ``jvl-gym studio``,
:mod:`.program` ``jvl-gym program``, :mod:`.precompile` ``jvl-gym compile``, :mod:`.demo` the
demo job of ``make demo``. A new command group is a module here, added to :mod:`.main`.
"""
