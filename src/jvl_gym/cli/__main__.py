"""``python -m jvl_gym.cli``: the ``jvl-gym`` command."""

from .main import app

app()
