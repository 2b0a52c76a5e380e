"""``engine.jit.plain_arguments``: a compiled callee that callers pass constants compiles once."""

from numba import njit

from jvl_gym.engine.jit import plain_arguments


def _pick(flag, k):  # pragma: no cover - compiled
    return 10 * k + (1 if flag else 2)


_plain = plain_arguments(njit(forceinline=True)(_pick))
_literal = njit(forceinline=True)(_pick)


@njit
def _calls_plain():  # pragma: no cover - compiled
    return _plain(True, 0) + 100 * _plain(False, 3)


@njit
def _calls_literal():  # pragma: no cover - compiled
    return _literal(True, 0) + 100 * _literal(False, 3)


def test_one_compiled_body_serves_every_constant_with_the_constants_own_results():
    assert _calls_plain() == 1 + 100 * 32
    assert len(_plain.signatures) == 1
    assert "Literal" not in str(_plain.signatures[0])


def test_without_it_numba_compiles_the_callee_once_per_constant():
    assert _calls_literal() == _calls_plain()
    assert len(_literal.signatures) == 2
    assert all("Literal" in str(sig) for sig in _literal.signatures)


def test_keyword_constants_are_plain_too():
    @njit
    def calls():  # pragma: no cover - compiled
        return _plain(flag=False, k=1) + _plain(True, k=2)

    assert calls() == 12 + 21
    assert len(_plain.signatures) == 1
