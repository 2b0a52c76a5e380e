"""The results page's transfer section: written from measured transfers, put into an existing
page in place of the one it had, the rest of the page left as it was."""

from __future__ import annotations

from jvl_gym.rl.results import TRANSFER_HEADING, write_transfer_section
from jvl_gym.rl.transfer import Transfer


def _transfer(deployed: float) -> Transfer:
    t = Transfer("jvl_gym/GearSync-v0", "mactalk:57600", 100000, 0.0384, sim=[1000.0, 1100.0],
                 link_model=[900.0, 1000.0], deployed=[deployed, deployed], reason="done",
                 rate_hz=26.0, latency_mean=0.004, latency_max=0.02, load=(3.0, 2.0, 1.0))
    t.label = "link"
    return t


def test_the_transfer_section_replaces_its_old_self_and_keeps_the_rest(tmp_path):
    page = tmp_path / "results.md"
    page.write_text("# Results\n\n## jvl_gym/GearSync-v0\n\nrows\n")
    write_transfer_section(page, [_transfer(855.0)])
    first = page.read_text()
    assert first.startswith("# Results\n\n## jvl_gym/GearSync-v0\n\nrows\n")
    row = next(line for line in first.splitlines() if line.startswith("| jvl_gym/GearSync"))
    # kept: 855 of the link model's 950 (90.0 %), of the simulation's 1050 (81.4 %)
    assert "| 90.0 % | 81.4 % | 26.0 Hz | 4.0 / 20.0 ms | 3.0 |" in row
    assert "| 1050.00 | 950.00 | 855.00 |" in row
    page.write_text(first + "\n## Later\n\nkept\n")
    write_transfer_section(page, [_transfer(950.0)])
    text = page.read_text()
    assert text.count(TRANSFER_HEADING) == 1 and "| 100.0 % |" in text
    assert text.rstrip().endswith("## Later\n\nkept") and "rows" in text
