"""Figure and panel references checked against the captions, and each caption's panel groups.

- a figure or panel: the panel exists in the caption's list, and every panel cited agrees with
  the caption on each property the sentence names (material, contact regime, vertical/lateral,
  amplitude/phase, grain, cantilever, kind of plot);
- a caption: panel groups that share a property split the panels without gaps.
"""
from __future__ import annotations

import re

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS
from pfmdyn.derivations.evidence import Evidence
from . import text as T


def _describe(caption, panel: str) -> str:
    d = caption.described.get(panel, {})
    return ", ".join(f"{cat} {'/'.join(sorted(w))}" for cat, w in sorted(d.items())) or "no property named"


def check_figure(ref: T.Reference):
    caps = T.captions()
    problems, notes, fixes = [], [], []
    named = T.keywords(ref.context)
    for fig, panels in ref.targets:
        cap = caps.get(fig)
        if cap is None:
            return Evidence(ERRATUM, f"no caption for Fig. {fig} (captions exist for {sorted(caps)})",
                            correction="a figure that exists")
        missing = [p for p in panels if p not in cap.panels]
        if missing:
            listed = ",".join(cap.panels) or "none"
            problems.append(f"Fig. {fig} has no panel {','.join(missing)} (caption lists panels {listed})")
            fits = [p for p in cap.panels if all(cap.described.get(p, {}).get(c, set()) & w for c, w in named.items())]
            fixes.append(f"Fig. {fig} {','.join(fits)}" if named and fits else
                         f"a panel of Fig. {fig} among {listed}")
            continue
        cited = panels or tuple(cap.described) or ("",)
        for cat, words in named.items():
            described = {p: cap.described.get(p, {}).get(cat) for p in cited}
            described = {p: w for p, w in described.items() if w}
            if not described:
                continue
            if panels:
                wrong = [p for p, w in described.items() if not (w & words)]
            else:                        # the whole figure: one panel agreeing is enough
                wrong = [] if any(w & words for w in described.values()) else list(described)
            if wrong:
                fits = [p for p in cap.panels if cap.described.get(p, {}).get(cat, set()) & words]
                fixes.append(f"Fig. {fig} {','.join(fits)}" if fits else f"a figure whose caption shows {'/'.join(sorted(words))}")
                problems.append(f"the sentence names {cat} {'/'.join(sorted(words))}, but the caption of Fig. {fig} "
                                f"gives " + "; ".join(f"panel {p}: {'/'.join(sorted(described[p]))}" for p in wrong)
                                + (f" (panels with {'/'.join(sorted(words))}: {','.join(fits)})" if fits else ""))
            else:
                notes.append(f"{cat} {'/'.join(sorted(words))} agrees with the caption")
        if panels:
            notes.append("caption: " + "; ".join(f"{p}: {_describe(cap, p)}" for p in panels))
    if problems:
        return Evidence(ERRATUM, "; ".join(problems), correction="; ".join(dict.fromkeys(fixes)))
    return Evidence(HOLDS, "; ".join(notes) or "the figure exists; the sentence names no property the caption describes")


# --- the panel groups of a caption ----------------------------------------------------------------

def check_caption_panels(number: int):
    """Within one caption: panel groups that share a property split the panels without gaps."""
    cap = T.captions()[number]
    problems, missing = [], set()
    for cat in sorted({c for d in cap.described.values() for c in d}):
        covered = [p for p in cap.panels if cat in cap.described.get(p, {})]
        if len(covered) < 4:
            continue
        gaps = [p for p in cap.panels if covered[0] < p < covered[-1] and p not in covered]
        if gaps:
            missing.update(gaps)
            problems.append(f"{cat}: panels {','.join(covered)} are described, panel {','.join(gaps)} "
                            f"(listed in the caption) is not")
    if problems:
        fixes = []
        for m in re.finditer(r"\(([a-l])\s*[-–]\s*([a-l])\)", cap.text):
            before = chr(ord(m.group(1)) - 1)
            if before in missing:
                fixes.append(f"({m.group(1)}-{m.group(2)}) should read ({before}-{m.group(2)})")
        return Evidence(ERRATUM, f"caption of Fig. {number}: " + "; ".join(problems),
                        correction="; ".join(fixes) or "describe every listed panel")
    return Evidence(HOLDS, f"caption of Fig. {number}: panels {','.join(cap.panels) or '(one)'}; every described "
                           "property covers its panels without gaps")
