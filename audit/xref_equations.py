"""Equation references checked against what the equations contain, and the numbering of the
equations.

- an equation: the label exists; the equation (with the ones printed under its "where") holds
  the symbols a limit in the sentence sends somewhere, the boundary-condition family a
  "free"/"clamped" reference needs, the trigonometric denominator a resonance needs, a bias
  dependence needs an electrostatic drive that the sentence did not set to zero;
- the numbering: equations are numbered 1, 2, 3, ... and sub-labels a, b, c, ... without gaps.
"""
from __future__ import annotations

import re
from functools import lru_cache

from pfmdyn.derivations import families as registry
from pfmdyn.derivations.checks.core import ERRATUM, HOLDS
from pfmdyn.derivations.evidence import Evidence, Tex, join, say
from . import text as T


_TRIG = re.compile(r"\\(?:sin|cos|tan|sinh|cosh)")


def _number(label: str) -> int:
    return int(re.match(r"\d+", label).group())


@lru_cache(maxsize=1)
def _solved() -> dict[int, tuple[str, range]]:
    """Equation number -> (the derivation that solves it, the numbers of its family's equations),
    from the family registry (``derivations/families.py``: ``equations`` such as 'Eqs. 27-28')."""
    out = {}
    for fam in registry.FAMILIES:
        m = re.fullmatch(r"Eqs?\. (\d+)(?:-(\d+))?", fam.equations)
        if m:
            numbers = range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1)
            out.update({n: (fam.derivation, numbers) for n in numbers})
    return out


@lru_cache(maxsize=1)
def _families() -> dict[str, str]:
    """Equation label -> the tip boundary condition it was solved with: the derivation the family
    registry names for its number, else the last boundary condition printed before it in its
    section (read from the printed conditions)."""
    family, out, section = "", {}, None
    for label in sorted(T.equations(), key=lambda s: (_number(s), s)):
        tex = T.equations()[label]
        if T.equation_section(label) != section:       # a family never carries over into another section
            family, section = "", T.equation_section(label)
        if re.search(r"u_0'*\(0\)", tex) and "(L)" not in tex:
            out[label] = "boundary condition"
        elif re.search(r"u_0'*\(L\)", tex) and "=" in tex:
            if "u_0(L) = 0" in tex:
                family = "pinned"
            elif "k_1" in tex or "k_2" in tex:
                family = "elastic_contact"
            elif "f_l" in tex:
                family = "sliding_friction"
            elif "f_0" in tex:
                family = "free_end"
            out[label] = "boundary condition"
        else:
            out[label] = _solved().get(_number(label), (family,))[0]
    return out


def _content(label: str) -> str:
    """The printed equation and, for the first equation of a family in the registry, the ones
    displayed under its 'where' (Eq. 5 with Eqs. 6-10)."""
    eqs = T.equations()
    tex = eqs.get(label, "")
    numbers = _solved().get(_number(label), ("", range(0)))[1]
    if label == str(numbers.start):
        tex += " ".join(eqs.get(str(i), "") for i in numbers[1:])
    return tex


def _labels(target: str) -> list[str]:
    eqs = T.equations()
    return [target] if target in eqs else [lab for lab in eqs if re.fullmatch(re.escape(target) + r"[a-f]", lab)]


def _before(ref: T.Reference) -> str:
    """The words between the previous equation reference of the sentence and this one."""
    starts = [r.start + len(r.text) for r in T.references()
              if r.sentence == ref.sentence and r.kind == "equation" and r.start < ref.start]
    return ref.sentence[max(starts, default=0):ref.start]


def _owns_phrase(ref: T.Reference, pattern: str) -> bool:
    """Does a phrase of the sentence speak about this reference (the nearest one before it,
    or the first one after it when none precedes)?"""
    eq_refs = [r for r in T.references() if r.sentence == ref.sentence and r.kind == "equation"] or [ref]
    for m in re.finditer(pattern, ref.sentence):
        before = [r for r in eq_refs if r.start < m.start()]
        owner = max(before, key=lambda r: r.start) if before else min(eq_refs, key=lambda r: r.start)
        if owner.start == ref.start:
            return True
    return False


def check_equation(ref: T.Reference):
    sentence = re.sub(r"\$\$.*?\$\$", " ", ref.sentence)
    sentence = re.sub(r"(?:below|above|near|far from) the (?:first )?resonan\w*", " ", sentence)
    notes, problems, fixes = [], [], []
    for target in ref.targets:
        labels = _labels(target)
        if not labels:
            return Evidence(ERRATUM, f"no equation is printed with label ({target})", correction="an equation that exists")
        tex = " ".join(_content(lab) for lab in labels)
        family = _families().get(labels[0], "")
        for sym in re.findall(r"\$([^$]*?)\\to", re.sub(r"\$\$.*?\$\$", " ", _before(ref))):
            sym = sym.strip().split("=")[-1].strip()
            if sym and sym not in tex:
                problems.append(say("the sentence takes ", Tex(sym), f" to a limit, but Eq. ({target}) has no ", Tex(sym)))
                fixes.append(say("an equation containing ", Tex(sym)))
        free_ref = _owns_phrase(ref, r"free cantilever")
        if free_ref and family not in ("free_end", "elastic_contact", ""):
            free = [lab for lab, fam in _families().items() if fam == "free_end"]
            fixes.append(say(f"Eq. ({', '.join(free)})"))
            problems.append(say(f"the sentence needs a free cantilever, but Eq. ({target}) is solved with the "
                            f"{family.replace('_', ' ')} tip conditions (free-end solution: Eq. ({', '.join(free)}))"))
        elif free_ref:
            notes.append(say(f"Eq. ({target}) is solved with {family.replace('_', ' ') or 'its own'} tip conditions ",
                             ("(the free end is its ", Tex("k_1 = k_2 = 0"), " case)") if family == "elastic_contact" else ""))
        if re.search(r"clamped end", sentence) and family == "boundary condition" and "(0)" not in tex:
            problems.append(say(f"Eq. ({target}) is not a condition at the clamped end ", Tex("x = 0")))
            fixes.append(say("Eq. (3a,b)"))
        if re.search(r"resonan|roots|denominator", sentence) and family != "boundary condition":
            if not _TRIG.search(tex):
                problems.append(say(f"the sentence needs resonances, but Eq. ({target}) has no frequency-dependent denominator"))
                fixes.append(say("an equation with a resonant denominator"))
            else:
                notes.append(say(f"Eq. ({target}) has a trigonometric (resonant) denominator"))
        if re.search(r"potential difference|\\Delta V|bias", sentence) and family not in ("boundary condition",):
            zeroed = set(re.findall(r"\$(f|f_0|q_0|d_1)\s*=\s*0\$", sentence))
            drives = {d for d in ("f_0", "q_0") if d in tex} - {("f_0" if z == "f" else z) for z in zeroed}
            if re.search(r"\\Delta V|potential difference", sentence) and not drives and re.search(r"calculated|according", sentence):
                with_q0 = [lab for lab in T.equations() if "q_0" in _content(lab) and _TRIG.search(_content(lab))
                           and _families().get(lab) not in ("boundary condition",)]
                fixes.append(say("an equation with the distributed load ", Tex("q_0"),
                                 f", e.g. Eq. ({with_q0[0]})" if with_q0 else ""))
                present = [Tex(d) for d in ("f_0", "q_0") if d in tex]
                problems.append(say(f"the sentence computes a bias dependence from Eq. ({target}), whose electrostatic "
                                    "drives ", join([(t,) for t in present], ", ") or "none", " the sentence sets "
                                    "to zero or lacks (no ", Tex("q_0"), ": no non-local term)"))
        purely = re.findall(r"purely (electromechanical|electrostatic)", sentence)
        if len(set(purely)) == 1 and family not in ("boundary condition",):
            drives = {d for d in ("d_1", "f_0", "q_0") if d in tex}
            want = {"electromechanical": {"d_1"}, "electrostatic": {"f_0", "q_0"}}[purely[0]]
            if drives and not drives <= want:
                problems.append(say(f"Eq. ({target}) has drives ", _drives(drives), f", not only {purely[0]} ones"))
                fixes.append(say(f"Eq. ({target}) with the other drives set to zero"))
            else:
                notes.append(say(f"Eq. ({target}) drives: ", _drives(drives), f" ({purely[0]})"))
        if re.search(r"boundary condition", sentence) and family == "boundary condition":
            for term in re.findall(r"u_0'+\(L\)", sentence):
                if term not in tex:
                    problems.append(say(f"Eq. ({target}) does not contain ", Tex(term)))
                    fixes.append(say("the boundary condition on ", Tex(term)))
            terms = sorted(set(re.findall(r"u_0'*\([L0]\)", tex)))
            notes.append(say(f"Eq. ({target}) is a boundary condition on ", _drives(terms)))
        notes.append(say(f"Eq. ({target}) printed in Section {T.equation_section(labels[0])}"))
    if problems:
        return Evidence(ERRATUM, join(problems), correction=join(dict.fromkeys(fixes)))
    return Evidence(HOLDS, join(dict.fromkeys(notes)))


def _drives(names) -> tuple:
    """LaTeX names (``d_1``, ``u_0(L)``) as formulas, sorted, separated by commas."""
    return join([(Tex(n),) for n in sorted(names)], ", ")


# --- numbering ------------------------------------------------------------------------------------

def check_equation_numbering():
    labels = sorted(T.equations(), key=lambda s: (int(re.match(r"\d+", s).group()), s))
    numbers = sorted({int(re.match(r"\d+", lab).group()) for lab in labels})
    gaps = [n for n in range(1, max(numbers) + 1) if n not in numbers]
    letter_gaps = []
    for n in numbers:
        letters = sorted(lab[len(str(n)):] for lab in labels if re.fullmatch(rf"{n}[a-f]?", lab) and lab != str(n))
        if letters:
            want = [chr(c) for c in range(ord("a"), ord(letters[-1]) + 1)]
            letter_gaps += [f"{n}{x}" for x in want if x not in letters]
    evidence = f"{len(labels)} labels, equations 1-{max(numbers)}; missing numbers: {gaps or 'none'}; " \
               f"missing sub-labels: {letter_gaps or 'none'}"
    if gaps or letter_gaps:
        relabel = []
        for gap in letter_gaps:
            n, letter = re.match(r"(\d+)([a-f])", gap).groups()
            later = [lab for lab in labels if re.fullmatch(rf"{n}[a-f]", lab) and lab[-1] > letter]
            if later:
                relabel.append(f"({later[0]}) should be ({gap})")
        return Evidence(ERRATUM, evidence, correction="; ".join(relabel) or "number the equations without gaps")
    return Evidence(HOLDS, evidence)
