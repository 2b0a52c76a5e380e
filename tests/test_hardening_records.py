"""Record CSV files: every malformed file is a RecordError naming the file and line."""

from __future__ import annotations

import pytest
from tuning.models import MotorData
from tuning.records import RecordError, load_csv, save_csv, simulate_testa, simulate_testu

MD = MotorData.from_config("MAC140")


def _good_testu(tmp_path):
    return save_csv(simulate_testu(MD, 100, 20), tmp_path / "u.csv")


def _lines(path):
    return path.read_text().splitlines()


def _write(path, lines):
    path.write_text("\n".join(lines) + "\n")
    return path


def test_good_files_load(tmp_path):
    assert load_csv(_good_testu(tmp_path)).n == 20
    rec = simulate_testa(MD, 5e-5, 50, 20)
    rec.meta["registers"] = {"KIFX2": 1.2, "PHASE_COMP": 5.0, "AMPLITUDE": 0.828125}
    back = load_csv(save_csv(rec, tmp_path / "a.csv"))
    assert back.meta["registers"]["KIFX2"] == 1.2


def test_duplicate_columns_are_refused(tmp_path):
    path = _good_testu(tmp_path)
    lines = _lines(path)
    k = lines.index("sample,UA_VAL,IC_IST")
    lines[k] = "UA_VAL,UA_VAL,IC_IST"
    with pytest.raises(RecordError, match=rf"u.csv:{k + 1}:.*UA_VAL.*more than once"):
        load_csv(_write(path, lines))


def test_rows_out_of_order_are_refused(tmp_path):
    path = _good_testu(tmp_path)
    lines = _lines(path)
    k = lines.index("sample,UA_VAL,IC_IST") + 1
    lines[k:] = lines[k:][::-1]
    with pytest.raises(RecordError, match=rf"u.csv:{k + 1}:.*sample"):
        load_csv(_write(path, lines))


@pytest.mark.parametrize("registers", ["KIFX2=nan", "KIFX2=1e9", "NO_SUCH=1", "KIFX2=inf",
                                       "KIFX2", "KIFX2=1 KIFX2=2", "V_IST=3"])
def test_bad_register_headers_are_refused(tmp_path, registers):
    rec = simulate_testa(MD, 5e-5, 50, 20)
    path = save_csv(rec, tmp_path / "a.csv")
    lines = _lines(path)
    lines.insert(4, f"# registers: {registers}")
    with pytest.raises(RecordError, match=r"a.csv:5:.*registers"):
        load_csv(_write(path, lines))


def test_non_utf8_and_non_numeric_files_are_record_errors(tmp_path):
    path = tmp_path / "latin.csv"
    path.write_bytes("# kind: TESTU\n# motor: MAC140 \xe9\n".encode("latin-1"))
    with pytest.raises(RecordError, match="latin.csv.*UTF-8"):
        load_csv(path)
    path = _good_testu(tmp_path)
    lines = _lines(path)
    lines[-3] = "17,abc,5"
    with pytest.raises(RecordError, match=rf"u.csv:{len(lines) - 2}:.*abc"):
        load_csv(_write(path, lines))
    lines[-3] = "17,nan,5"
    with pytest.raises(RecordError, match=rf"u.csv:{len(lines) - 2}:.*finite"):
        load_csv(_write(path, lines))


def test_repeated_header_keys_are_refused(tmp_path):
    path = _good_testu(tmp_path)
    lines = _lines(path)
    lines.insert(2, "# kind: TESTA")
    with pytest.raises(RecordError, match="u.csv:3:.*kind"):
        load_csv(_write(path, lines))


def test_a_directory_is_not_a_record(tmp_path):
    with pytest.raises(RecordError, match="not found"):
        load_csv(tmp_path)
