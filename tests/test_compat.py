"""The previous release's names still work, each with a DeprecationWarning naming its new
place (docs/architecture.md, "The tree"): every module path of the previous layout
(``jvl_gym.compat.MOVED``) imports as the module at its new place (the same object), ``python
-m`` with an old name runs the new module, and renamed methods call their new names."""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings

import pytest

from jvl_gym.compat import MOVED, renamed_method


@pytest.mark.parametrize("old, new", sorted(MOVED.items()))
def test_an_old_module_name_is_the_new_module_and_warns(old: str, new: str) -> None:
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{old} is deprecated .*import {new}"):
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert module.__spec__.name == new  # the new module keeps its own spec
    assert module.__name__ == new


def test_an_old_name_is_refused_as_any_missing_module_when_it_was_never_moved() -> None:
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("jvl_gym.no_such_module")


def test_python_m_with_an_old_module_name_runs_the_new_module() -> None:
    new = subprocess.run([sys.executable, "-m", "jvl_gym.cli_serve", "--help"],
                         capture_output=True, text=True, timeout=120)
    assert new.returncode == 0, new.stderr
    assert "--motor" in new.stdout
    shown = subprocess.run([sys.executable, "-W", "default", "-m", "jvl_gym.cli_serve", "--help"],
                           capture_output=True, text=True, timeout=120)
    assert "jvl_gym.cli_serve is deprecated: run jvl_gym.cli.serve" in shown.stderr


class _Old:
    def new_name(self, x: int, *, y: int = 0) -> int:
        return x + y

    old_name = renamed_method("new_name", "old_name")


class _Override(_Old):
    def new_name(self, x: int, *, y: int = 0) -> int:
        return -x


def test_a_renamed_method_warns_and_calls_the_new_name_of_the_subclass() -> None:
    with pytest.warns(DeprecationWarning, match="_Old.old_name is deprecated .* use new_name"):
        assert _Old().old_name(2, y=3) == 5
    with pytest.warns(DeprecationWarning):
        assert _Override().old_name(2) == -2
    assert _Old.old_name.__name__ == "old_name"


def test_the_clients_and_the_array_keep_their_previous_method_names() -> None:
    from jvl_gym.motor.array import MotorArray
    from jvl_gym.protocol.mactalk.client16 import MacTalkClient
    from jvl_gym.protocol.mactalk.client32 import MacTalk32Client

    for cls, pairs in ((MotorArray, [("go_safe_mode", "enter_safe_mode")]),
                       (MacTalkClient, [("go_safe_mode", "enter_safe_mode"),
                                        ("reset", "software_reset"),
                                        ("read_sample_buffer", "sample_buffer"),
                                        ("read_sample_buffer_raw", "sample_buffer_raw")]),
                       (MacTalk32Client, [("go_init_mode", "exit_safe_mode"),
                                          ("go_safe_mode", "enter_safe_mode")])):
        for old, new in pairs:
            assert callable(getattr(cls, new))
            assert f":meth:`{new}`" in getattr(cls, old).__doc__


def test_the_array_s_old_safe_mode_name_enters_safe_mode() -> None:
    from jvl_gym import MotorArray

    m = MotorArray("MAC140", n=1, seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m.go_safe_mode()
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)
    assert m.mode_name(0) == m.family.constants.MODE_NAMES[m.family.twin.safe_mode]
