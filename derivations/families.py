"""The family registry: the one list of boundary-condition families and their names.

A family is one set of tip conditions for Eq. 2.  Each :class:`Family` row names

* ``module``: the generated module (``generated/<module>.py``);
* ``derivation``, ``solver``: where it is derived (``derivations/<derivation>.py: <solver>()``);
* ``drives`` and ``parameters``: argument names of the generated functions, in order;
* ``outputs``: the generated functions (``slope``, ``deflection`` or ``twist``);
* ``roots``: the name under which ``pfmdyn roots`` and ``pfmdyn branches`` know its
  characteristic function (``None``: not offered there);
* ``function``, ``result``: the public wrapper in :mod:`pfmdyn.transfer` and its result
  class (``None``: no wrapper);
* ``kind``: ``flexural`` or ``torsion`` (which renderer writes it);
* ``branch``, ``figure``: the stiffness parameter ``pfmdyn branches`` sweeps, and the
  paper's figure the sweep reproduces (``None``: no branch diagram);
* ``method``: the :class:`pfmdyn.Cantilever` method evaluating it in SI units at
  frequencies in Hz, with the cantilever's losses (``None``: none);
* ``chapter``: the book page (``book/<chapter>.md``) deriving it (``None``: discussed where
  it is used, not in a family chapter).

Codegen, the root finders and the transfer wrappers all read this table (numeric code
through ``generated/families.py``, written from it).  Plain data: importing it needs no
SymPy.  Rows are in the order families are listed to users.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Family", "FAMILIES", "PARAMETER_HELP", "by_module"]


@dataclass(frozen=True)
class Family:
    """One boundary-condition family (see the module docstring for the fields)."""

    module: str
    derivation: str
    solver: str
    equations: str
    drives: tuple[str, ...]
    parameters: tuple[str, ...]
    outputs: tuple[str, ...] = ("slope",)
    roots: str | None = None
    function: str | None = None
    result: str | None = None
    kind: str = "flexural"
    branch: str | None = None
    figure: str | None = None
    method: str | None = None
    chapter: str | None = None

    @property
    def source(self) -> str:
        """Where the family is derived, as quoted in generated headers."""
        return f"derivations/{self.derivation}.py: {self.solver}()"


_CONTACT = ("d1", "d2", "f0", "q0")

FAMILIES: tuple[Family, ...] = (
    Family("free_end", "free_end", "solve", "Eqs. 21-22", ("f0", "q0"), ("k", "L"),
           roots="free", function="free_end_transfer", result="FreeEndTransfer",
           method="free_response", chapter="free_end"),
    Family("pinned", "pinned", "solve", "Eqs. 19-20", ("q0",), ("k",),
           roots="pinned", function="pinned_transfer", result="PinnedTransfer",
           method="pinned_response", chapter="pinned"),
    Family("elastic_contact", "elastic_contact", "solve", "Eqs. 5-10", _CONTACT,
           ("k", "k1", "k2", "H", "L"),
           roots="elastic", function="tip_slope_transfer", result="ElasticTransfer",
           branch="k2_ratio", figure="Fig. 4e",
           method="elastic_response", chapter="elastic_contact"),
    Family("frictionless", "frictionless", "solve", "Eq. 23", ("d1", "f0", "q0"), ("k", "k1", "L"),
           roots="frictionless", function="frictionless_transfer", result="FrictionlessTransfer",
           branch="k1_over_k", figure="Fig. 4b",
           method="frictionless_response", chapter="frictionless"),
    Family("frictionless_stiff", "frictionless", "solve_stiff", "Eq. 24", ("d1", "q0"), ("k", "L"),
           function="frictionless_stiff_transfer", result="FrictionlessStiffTransfer",
           chapter="frictionless"),
    Family("sliding_friction", "sliding_friction", "solve", "Eqs. 25-26", ("f_l",), ("k", "H", "L"),
           roots="friction", function="sliding_friction_transfer", result="FrictionTransfer",
           method="sliding_friction_response", chapter="sliding_friction"),
    Family("indentation", "indentation", "solve", "Eqs. 27-28", ("d1", "f0"), ("k", "k1", "L"),
           outputs=("slope", "deflection"),
           roots="indentation", function="indentation_transfer", result="IndentationTransfer",
           branch="k1_over_k", figure="Fig. 4b",
           method="indentation_response", chapter="indentation"),
    Family("indentation_stiff", "indentation", "solve_stiff", "Eq. 29", ("d1",), ("k", "L"),
           function="indentation_stiff_transfer", result="IndentationStiffTransfer",
           chapter="indentation"),
    Family("tip_mass", "tip_mass", "solve", "Eqs. 4-5 with tip inertia", _CONTACT,
           ("k", "k1", "k2", "H", "L", "mu")),
    Family("tilt", "tilt", "solve", "Eqs. 4-5 with a tilted cantilever", _CONTACT,
           ("k", "kvv", "kll", "kvl", "H", "L")),
    Family("torsion_elastic", "torsion", "solve_elastic", "Eqs. 32-33", ("d3",), ("k2t", "H", "L"),
           outputs=("twist",), roots="torsion-elastic", function="torsion_elastic_transfer",
           result="TorsionTransfer", kind="torsion", branch="k2t_HL", figure="Fig. 5c",
           chapter="torsion"),
    Family("torsion_force", "torsion", "solve_force", "Eqs. 34-35", ("f_lat",), ("L",),
           outputs=("twist",), roots="torsion-force", function="torsion_force_transfer",
           result="TorsionTransfer", kind="torsion",
           chapter="torsion"),
)
"""Every family with a generated module."""

PARAMETER_HELP = {
    "k": "cantilever spring constant k = 3 EI / L**3 (N/m)",
    "k1": "vertical contact stiffness (N/m)",
    "k2": "longitudinal contact stiffness (N/m)",
    "H": "tip height (m)",
    "L": "cantilever length (m)",
    "mu": "tip mass over beam mass",
    "rho_g": "tip radius of gyration over cantilever length, r_g / L (J = m_tip r_g**2)",
    "kvv": "vertical contact stiffness in beam axes (N/m)",
    "kll": "longitudinal contact stiffness in beam axes (N/m)",
    "kvl": "vertical-longitudinal coupling stiffness in beam axes (N/m)",
    "gamma": "tip position over cantilever length, 0 < gamma <= 1",
    "k2t": "lateral contact stiffness over the torsional rigidity, H k2 / c_T (1/m**2)",
    "k1_over_k": "k1/k: vertical contact stiffness over the cantilever spring constant",
    "k2_ratio": "k2 H^2/(k L^2): longitudinal contact stiffness seen through the lever arm H",
    "k2t_HL": "H^2 k2 L/c_T: lateral contact stiffness over the torsional stiffness",
}
"""Parameter name -> meaning (dimensional parameters with units; dimensionless ones last)."""


def by_module(module: str) -> Family:
    """The family whose generated module is ``module``.

    >>> by_module("elastic_contact").roots
    'elastic'
    """
    return next(f for f in FAMILIES if f.module == module)
