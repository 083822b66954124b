"""The one description of the probe: names, the composed model behind it, the tilt sign."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import Cantilever, Contact
from pfmdyn.errors import UserError
from pfmdyn.names import NAMES, canonical, markdown_table

ROOT = Path(__file__).resolve().parents[1]


def test_readme_has_the_table_of_names():
    assert markdown_table() in (ROOT / "README.md").read_text()


def test_every_name_has_one_flag_and_reads_its_old_spellings():
    flags = [q.flag for q in NAMES.values()]
    assert len(set(flags)) == len(flags)
    for old, new in [("spring_constant_n_per_m", "spring_constant"), ("free_resonance_hz", "free_resonance"),
                     ("length_m", "length"), ("tip_height_m", "tip_height"), ("width_m", "width")]:
        assert canonical(old) == new


def _levers(seed, count):
    """Levers over real ranges: k 0.05-50 N/m, L 100-500 um, f1 from k and L, k1/k 1-1e4, Q 5-500."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        k = 10 ** rng.uniform(np.log10(0.05), np.log10(50))
        length = rng.uniform(100e-6, 500e-6)
        f1 = 10 ** rng.uniform(4, 6)
        yield (Cantilever(k, f1, length, quality_factor=10 ** rng.uniform(np.log10(5), np.log10(500)),
                          tip_height=rng.uniform(3e-6, 20e-6)),
               k * 10 ** rng.uniform(0, 4), rng.uniform(0, 1.2))


def test_composed_model_is_the_paper_family_for_the_paper_probe():
    """Independent route: the paper's family function (Eq. 5) against the composed set-back model."""
    for lever, k1, ratio in _levers(7, 12):
        f = lever.free_resonance * np.geomspace(0.3, 60, 40)
        composed = lever.response(f, Contact(k1=k1, k2=ratio * k1))
        family = lever.elastic_response(f, k1=k1, k2=ratio * k1, H=lever.tip_height)
        for a, b in zip(composed, family):
            np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-12 * np.abs(b).max())


def test_family_methods_refuse_a_lever_they_do_not_describe():
    lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, tip_position=0.93)
    with pytest.raises(UserError, match="Cantilever.response"):
        lever.elastic_response([1e5], k1=100.0, k2=0.0, H=1e-5)


def test_tilt_sign_is_stated_once():
    """Public tilt > 0 (free end nearer the sample) is the derivations' alpha < 0."""
    assert Cantilever(2.0, 7e4, 2e-4, tilt=12.0).alpha == pytest.approx(-math.radians(12.0))


def test_heavy_tip_lowers_the_free_root_and_the_lever_still_resonates_at_f1():
    lever = Cantilever(2.0, 7e4, 2e-4, quality_factor=300.0, tip_mass_ratio=0.3)
    assert lever.free_root() < 1.8751
    f = np.linspace(6e4, 8e4, 4001)
    free = lever.response(f, Contact(k1=0.0)).local_force
    assert f[np.argmax(np.abs(free))] == pytest.approx(7e4, rel=2e-3)


def test_bad_values_are_one_line_errors():
    with pytest.raises(UserError, match="tip_position"):
        Cantilever(2.0, 7e4, 2e-4, tip_position=1.3)
    with pytest.raises(UserError, match="not several"):
        Contact(k1=1.0, k2=1.0, poisson=0.3)
    with pytest.raises(UserError, match="tip_height"):
        Cantilever(2.0, 7e4, 2e-4, tilt=10.0).response([1e5], Contact(k1=10.0))


def _options():
    """(command, option string, dest, shown in --help) for every option of every command."""
    import argparse
    import importlib

    from pfmdyn.cli import COMMANDS
    for command, (module, _) in COMMANDS.items():
        parser = argparse.ArgumentParser()
        importlib.import_module(module).add_arguments(parser)
        for action in parser._actions:
            for option in action.option_strings:
                yield command, option, action.dest, action.help != argparse.SUPPRESS


def test_every_command_spells_each_quantity_with_its_one_flag():
    """A quantity of pfmdyn.names is given by the same flag in every command (old spellings may
    survive only hidden from --help)."""
    wrong = [(c, o) for c, o, dest, shown in _options()
             if dest in NAMES and shown and o.startswith("--") and o != NAMES[dest].flag]
    assert not wrong, wrong
    retired = {"--k", "--tip-mass", "--free", "--free-hz", "--L", "--H"}
    assert not [(c, o) for c, o, _, shown in _options() if o in retired and shown]


# Options of a quantity not (yet) made by the shared helpers, and why.
NOT_SHARED: set = set()       # (map's starting Q is --start-quality-factor, not the lever's Q)


def test_every_quantity_flag_comes_from_the_shared_helpers():
    """A quantity's flag is made by pfmdyn.commands.flags (its help states the quantity's meaning
    and unit from pfmdyn.names), so a command cannot give it another meaning or unit."""
    plain = {(c, o) for c, o, dest, shown in _options()
             if dest in NAMES and NAMES[dest].option and shown and o.startswith("--") and not _help(c, o).startswith(NAMES[dest].meaning)}
    assert plain == NOT_SHARED


def _help(command, option):
    import argparse
    import importlib

    from pfmdyn.cli import COMMANDS
    parser = argparse.ArgumentParser()
    importlib.import_module(COMMANDS[command][0]).add_arguments(parser)
    return next(a.help for a in parser._actions if option in a.option_strings) or ""


def test_diagram_keeps_the_papers_values_when_not_given(tmp_path):
    """--k1, --tip-height, --quality-factor of diagram: shared flags with the paper's defaults."""
    import argparse

    from pfmdyn.analysis.diagram import PAPER_K1, PAPER_TIP_HEIGHT
    from pfmdyn.commands import diagram
    parser = argparse.ArgumentParser()
    diagram.add_arguments(parser)
    args = parser.parse_args(["--out", "x.png"])
    assert (args.k1, args.tip_height, args.quality_factor) == (PAPER_K1, PAPER_TIP_HEIGHT, None)
    from pfmdyn.cli import main
    assert main(["diagram", "--out", str(tmp_path / "d.png"), "--k1", "-5"]) == 2
    assert not (tmp_path / "d.png").exists()


def test_instrument_records_and_inspect_json_use_the_names():
    """Record fields are names of pfmdyn.names; files with the older spellings are read under them."""
    from pfmdyn.io.record import FIELDS, make_record
    assert set(FIELDS) <= set(NAMES)
    record = make_record("a.ibw", "image", "test", (), {"contact_resonance_hz": 3e5, "tip_bias_v": -1.5,
                                                        "length_m": 2e-4, "free_quality_factor": 80.0})
    assert record.to_json()["fields"] == {"free_quality_factor": {"value": 80.0, "unit": ""},
                                          "contact_resonance": {"value": 3e5, "unit": "Hz"},
                                          "length": {"value": 2e-4, "unit": "m"},
                                          "tip_bias": {"value": -1.5, "unit": "V"}}
    assert "spring_constant" in record.missing and "tip_height" in record.missing
