"""Benchmark: the shared before/after drive-sweep pairs (``/work/shared/realdata/pyimd_cantilever_sweeps``)
explained by ``pfmdyn discrepancy AFTER --reference BEFORE`` beside pyIMD's first-mode mass.

Run ``python benchmarks/pyimd_pairs.py`` (needs ``pip install --no-deps pyimd==0.0.8``: pyIMD's own
functions are called, not re-implemented).  Results: ``benchmarks/results/pyimd_pairs.md``
(:mod:`recording`).

pyIMD (``pyIMD/analysis``): each sweep's phase fitted by a harmonic oscillator's phase plus a linear
phase background (``calculate_resonance_frequencies``, pyIMD's default guess and bounds, kHz and rad
as pyIMD converts them: degrees over -57.3), then ``calculate_mass(k, f_after, f_before)`` (``k / (4 pi**2) (1/f_A**2 -
1/f_B**2)``, ng) times ``calculate_position_correction(d, L)`` (the first mode's shape at ``d`` from
the free end).  pfmdyn: the whole complex sweep, a base-driven beam in water (Sader's load), gain and
background, before's lever kept, the mass a point mass on the beam (:mod:`pfmdyn.discrepancy.sweep`).
"""
from __future__ import annotations

import time
from pathlib import Path

from recording import recorded

from pfmdyn.discrepancy.reference import compare_sweeps
from pfmdyn.discrepancy.sweep import fit_sweep
from pfmdyn.io.sweeps import read_sweep_table
from pfmdyn.medium import Medium

DATA = Path("/work/shared/realdata/pyimd_cantilever_sweeps")

# pair -> (before, after, spring constant N/m, length m, cell distance from the free end m, where they come from)
PAIRS = {
    "RSN_3": ("20170712_RSN_3_B.txt", "20170712_RSN_3_A.txt", 8.0, 100e-6, 9.5e-6,
              "pyIMD/examples/example_usage_script.py"),
    "LC_05": ("20190510_LC_05_B001.dat", "20190510_LC_05_A001.dat", 8.0, 100e-6, 10e-6,
              "pyIMD/examples/example_usage_script_nanonis_longterm.py"),
    "SBC_3_C_4": ("20180628_SBC_3_C_4_B.txt", "20180628_SBC_3_C_4_A.txt", 4.0, 100e-6, 5e-6,
                  "not in any pyIMD script: pyIMD's defaults (k 4 N/m, L 100 um, cell 5 um), not this lever's"),
    "ShowCase_PLL": ("20190110_ShowCase_PLL_B.txt", "20190110_ShowCase_PLL_A.txt", 4.0, 100e-6, 5e-6,
                     "not in any pyIMD script: pyIMD's defaults; both headers identical (suspect)"),
}


def pyimd(before, after, k, length, distance):
    """pyIMD 0.0.8's phase fits and first-mode mass (kg) of the pair."""
    from pyIMD.analysis.calculations import (calculate_mass, calculate_position_correction,
                                             calculate_resonance_frequencies)
    from pyIMD.configuration.defaults import (CONVERSION_FACTOR_DEG_TO_RAD, CONVERSION_FACTOR_HZ_TO_KHZ,
                                              INITIAL_PARAMETER_GUESS, LOWER_PARAMETER_BOUNDS,
                                              UPPER_PARAMETER_BOUNDS)

    fits = []
    for table in (before, after):
        # pyIMD's own conversion (imd.py, convert_data): kHz, and degrees over -57.3 (its phase sign)
        f_khz, phase = table.frequency_hz / CONVERSION_FACTOR_HZ_TO_KHZ, table.phase_deg / CONVERSION_FACTOR_DEG_TO_RAD
        f0, params = calculate_resonance_frequencies(f_khz, phase, INITIAL_PARAMETER_GUESS, LOWER_PARAMETER_BOUNDS,
                                                     UPPER_PARAMETER_BOUNDS)
        fits.append((f0 * 1e3, params[0]))
    correction = calculate_position_correction(distance * 1e6, length * 1e6)
    mass = calculate_mass(k, fits[1][0] / 1e3, fits[0][0] / 1e3) * correction * 1e-12     # ng -> kg
    header = calculate_mass(k, after.header_frequency[1] / 1e3, before.header_frequency[1] / 1e3)
    return fits, correction, mass, header * correction * 1e-12


def main() -> None:
    rows, notes = [], []
    for name, (b, a, k, length, distance, source) in PAIRS.items():
        before, after = read_sweep_table(DATA / b), read_sweep_table(DATA / a)
        t0 = time.perf_counter()
        fit = fit_sweep(before, k, length, Medium.water())
        placed = compare_sweeps(after, fit, 1 - distance / length)
        end = compare_sweeps(after, fit, None)
        seconds = time.perf_counter() - t0
        ((fb, qb), (fa, qa)), correction, m_pyimd, m_header = pyimd(before, after, k, length, distance)
        p = placed["parameters"]["added_mass"]
        rows.append(f"| {name} | {k:g}, {length * 1e6:g}, {distance * 1e6:g} | "
                    f"{before.header_frequency[1]:.0f} / {before.fields['free_quality_factor']:.2f} -> "
                    f"{after.header_frequency[1]:.0f} / {after.fields['free_quality_factor']:.2f} | "
                    f"{fb:.0f} / {qb:.2f} -> {fa:.0f} / {qa:.2f} | "
                    f"{fit.lever.free_resonance:.0f} / {fit['quality_factor']:.2f} -> {placed['resonance_after']:.0f} | "
                    f"{fit['gap']:.2f}; {placed['gap_before']:.2f} -> {placed['gap_after']:.2f} | "
                    f"{placed['effect']} ({', '.join(placed['nuisances']) or 'no nuisance'}) | "
                    f"{m_pyimd * 1e15:.0f} (header f: {m_header * 1e15:.0f}) | "
                    f"{p['value'] * 1e15:.0f} +- {p['stderr'] * 1e15:.0f} | "
                    f"{end['parameters']['added_mass']['value'] * 1e15:.0f} | {seconds:.1f} |")
        notes.append(f"* {name}: constants from {source}; pyIMD's position correction {correction:.3f}.")
    text = [
        "# The shared before/after drive sweeps: pfmdyn beside pyIMD",
        "",
        "Written by `benchmarks/pyimd_pairs.py` (pyIMD 0.0.8 from PyPI, installed with `--no-deps`; its own",
        "`calculate_resonance_frequencies`, `calculate_mass`, `calculate_position_correction` are called).",
        "Frequencies in Hz, masses in pg (1e-15 kg), k in N/m, L and the cell's distance from the free end in um.",
        "pfmdyn: `fit_sweep` on before in water at 20 C (width not given: L/10 assumed, the damping beyond the",
        "fluid's fitted), `compare_sweeps` on after at x/L = 1 - d/L, and with the position not given (one mode:",
        "undetermined, the end-equivalent mass).  The gaps: before's fit; after with before's model as is -> the",
        "named explanation.",
        "",
        "| pair | k, L, d | header f (Cytomass: amplitude peak; Nanonis: f_res) / Q (B -> A) | pyIMD phase fit f / Q | pfmdyn f in water / Q -> f after |"
        " gap B; A | pfmdyn names | pyIMD mass | pfmdyn mass at d | pfmdyn end-equivalent | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        *notes,
        "",
        "## Why the masses differ",
        "",
        "* **The first-order formula.** pyIMD converts the shift with `k / (4 pi^2) (1/f_A^2 - 1/f_B^2)`: the",
        "  lever as a spring and a point mass, the whole shift from the cell.  pfmdyn puts the cell on the",
        "  beam (a point mass in the composed model) and asks what mass moves the beam's resonance by the",
        "  observed amount; it needs no first-mode position factor (the mode shape is in the beam), and its",
        "  end-equivalent mass is what a mass at the free end would have to be.",
        "* **The fluid.** In water the lever moves with the liquid it entrains (Sader's load: about as heavy",
        "  as the lever or heavier at these sizes), and that load grows as the frequency falls: a given mass",
        "  lowers the resonance less than in vacuum, and the formula, which reads the in-liquid frequencies",
        "  as if the lever's own mass set them, ignores the change of the fluid's share.",
        "* **The fitting model.** pyIMD fits the phase alone of a simple harmonic oscillator with a linear",
        "  phase background; pfmdyn fits the complex response of the base-driven beam (every mode, the fluid",
        "  load at each frequency) with a complex gain and a linear complex background.  With Q about 3",
        "  the peak is a few tens of kHz wide and the background is strong, so the two fits place the",
        "  resonance differently (by 6 Hz to 1.1 kHz here; the header's amplitude peak 1-2 kHz lower still).",
        "* **Nuisances.** Between the two sweeps the gain and the background change (laser, re-approach)",
        "  and the cell adds drag (LC_05: header Q 6.85 -> 5.50); pfmdyn refits them and names them beside",
        "  the mass (BIC over the candidates: without the damping LC_05's after-sweep keeps a gap of 4.1,",
        "  with it 1.03); pyIMD assumes the whole change of the phase-fit frequency is the mass.",
        "* **The headers.** The Cytomass `Peak amplitude frequency` is the amplitude's peak, 1-2 kHz below",
        "  the phase fit's resonance; its `Centre frequency` is the phase fit's (pyIMD's fit reproduces it",
        "  to 1 Hz), which is what pyIMD and pfmdyn compare.  pyIMD's default bounds cap Q at 5: the LC_05",
        "  and ShowCase fits sit on that bound.  pyIMD's mass from the header's peak frequencies is shown in",
        "  brackets; the two ShowCase headers are identical, so it is 0.",
        "* **Uncertainty.** pfmdyn's +- is the fit's (reduced-chi2-scaled) standard error; the assumed width",
        "  (L/10) moves RSN_3's mass by about 4 % between widths of 1 and 30 um, LC_05's by about 25 %.",
        "",
    ]
    print("\n".join(text))


if __name__ == "__main__":
    with recorded("pyimd_pairs"):
        main()
