"""Code generation: the derived transfer functions as stable NumPy code in ``generated/``.

The family registry (:mod:`derivations.families`) says what is generated.  The package:

* :mod:`.printing`: printer, CSE, Horner series, header and source hash;
* :mod:`.stabilise`: split by parameter monomial, switch point, series branch, clipped exp;
* :mod:`.examples`: the stored point and the doctest values computed there from SymPy;
* :mod:`.templates`: one Jinja template per output kind (``templates/``), filled by its renderer;
* one renderer per output kind: :mod:`.transfer` (one module per one-argument family),
  :mod:`.characteristic` (``characteristic.py``, for root finding), :mod:`.pieces`
  (``lever_pieces.py``, the pieces the composed lever is assembled from), :mod:`.registry` (``families.py``, the family
  registry as plain data for numeric code), :mod:`.inputs` (``paper_inputs.py``),
  :mod:`.formulas` (``formulas.py``, closed-form relations), :mod:`.effects` (``damping.py``, ``tilt_rotation.py``: the discrepancy
  model's damping substitution and tilt rotation, with their derivatives);
* :mod:`.jacobian`: the partial derivatives generated with the transfer functions
  (``<function>_and_jacobian`` in the modules of :data:`.jacobian.JACOBIANS`, rendered by
  :mod:`.transfer`).

:func:`render_all` maps every output file name to its text; a renderer is added by adding
its files there.  A ``.py`` file in ``generated/`` that no renderer writes (and not in
:data:`HAND_WRITTEN`) is an orphan, and ``pfmdyn codegen --check`` fails on it.  Run
through ``pfmdyn codegen`` (see :mod:`pfmdyn.commands.codegen`).
"""
from __future__ import annotations

from pathlib import Path

from ..trig import from_atoms
from . import effects, formulas, inputs, pieces, registry
from .characteristic import characteristic_families, dimensionless, render_characteristic
from .examples import beta1_free
from .stabilise import series_branch, split, switch_point
from .transfer import Family, Function, families, render_family

__all__ = ["Function", "Family", "families", "split", "from_atoms", "series_branch", "switch_point",
           "render_family", "characteristic_families", "dimensionless", "beta1_free",
           "render_characteristic", "render_all", "write", "GENERATED", "HAND_WRITTEN"]

GENERATED = Path(__file__).resolve().parent.parent.parent / "generated"
"""The committed output folder (``generated/`` at the repository root)."""

HAND_WRITTEN = ("__init__.py",)
"""Files of ``generated/`` that no renderer writes and that are not orphans."""


def render_all() -> dict[str, str]:
    """File name -> text of every generated file (deterministic)."""
    files = {f"{fam.module}.py": render_family(fam) for fam in families()}
    files["characteristic.py"] = render_characteristic()
    files["lever_pieces.py"] = pieces.render()
    files["families.py"] = registry.render()
    files["paper_inputs.py"] = inputs.render()
    files["formulas.py"] = formulas.render()
    files["damping.py"] = effects.render_damping()
    files["tilt_rotation.py"] = effects.render_rotation()
    return dict(sorted(files.items()))


def write(folder: Path, files: dict[str, str] | None = None) -> list[str]:
    """Write every generated file (``files``, default :func:`render_all`) into ``folder``;
    return the names of files that changed."""
    folder.mkdir(parents=True, exist_ok=True)
    changed = []
    for name, text in (render_all() if files is None else files).items():
        path = folder / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            changed.append(name)
    return changed
