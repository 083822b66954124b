"""The resonances of Section VI.1 of the paper (Jesse et al. 2006) as input tables: the test,
benchmark and book fixture of ``pfmdyn discrepancy`` on measured resonances.

The paper gives no tip height for these levers: 10 um is assumed here.
"""
from __future__ import annotations

import numpy as np

from pfmdyn.generated import paper_inputs
from pfmdyn.io.tables import Metadata, ResonanceData


def paper_tables() -> dict[str, ResonanceData]:
    """Section VI.1 resonances as input tables (tip 1: contact and non-contact; tip 2: free).

    The cantilever is the one specified for tip 2 (w = 24 um, L = 223 um, k = 2.4 N/m;
    the paper's h = 3 um is the thickness).  Tip height is not given: 10 um is assumed.
    Tip 2 has no contact resonances in the text, so only its free modes are tabulated.
    """
    g = paper_inputs.TIP2_GEOMETRY

    def table(free, contact, sigma):
        free, contact = list(free), list(contact)
        modes = list(range(1, len(free) + 1)) + list(range(1, len(contact) + 1))
        conds = ["free"] * len(free) + ["contact"] * len(contact)
        meta = Metadata(spring_constant=g["k"], length=g["L"], width=g["w"], tip_height=10e-6,
                        free_resonance=free[0] * 1e3, description="Jesse et al. 2006, Section VI.1",
                        frequency_uncertainty_hz=sigma)
        return ResonanceData(meta, np.array(modes), np.array(conds), np.array(free + contact) * 1e3)

    return {"tip 1": table(paper_inputs.TIP1_FREE_KHZ, paper_inputs.TIP1_CONTACT_KHZ, 300.0),
            "tip 2": table(paper_inputs.TIP2_FREE_KHZ, (), 100.0)}
