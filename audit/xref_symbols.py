"""Symbols checked against their uses and definitions in the text.

- a symbol: it is defined (or used consistently), is not a one-off misspelling of another
  symbol, and is not defined twice with conflicting meanings.
"""
from __future__ import annotations

import re

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS, UNDECIDABLE
from pfmdyn.derivations.evidence import Evidence, Tex, join, say
from . import text as T


def _split(symbol: str) -> tuple[str, str, bool]:
    m = re.match(r"(\\tilde\{(\\?[A-Za-z]+)\}|\\?[A-Za-z]+)(?:_\{?([^{}]*)\}?)?$", symbol)
    if not m:
        return symbol, "", False
    tilde = bool(m.group(2))
    return (m.group(2) if tilde else m.group(1)), m.group(3) or "", tilde


def _edit(a: str, b: str) -> int:
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i]
        for j, cb in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb)))
        prev = cur
    return prev[-1]


def _neighbours(symbol: str) -> list[str]:
    """Symbols used more than once that this one-off symbol is one edit away from."""
    base, sub, tilde = _split(symbol)
    out = []
    for other, use in T.symbols().items():
        if other == symbol or use.uses < 2:
            continue
        ob, osub, otilde = _split(other)
        if ob != base:
            continue
        if tilde == otilde and len(sub) >= 2 and len(osub) >= 2 and _edit(sub, osub) == 1:
            out.append(other)
        elif tilde != otilde and sub == osub:
            out.append(other)
        elif tilde and otilde and not sub and osub:
            out.append(other)
    return out


def _used_in(symbol: str, tag: str) -> bool:
    sec = next((s for s in T.sections() if s.tag == tag), None)
    return bool(sec) and any(T.canonical(m.group(0)) == symbol for m in re.finditer(r"\\?[A-Za-z]+_(?:\{[^{}]+\}|.)", sec.body))


def _definitions(symbol: str) -> list[str]:
    """Right-hand sides printed as '$symbol = ...$' anywhere in the text."""
    pat = re.compile(r"\$\s*" + re.escape(symbol).replace(r"_", r"_\{?") + r"\}?\s*=\s*([^$]+)\$")
    # A value or a condition ("d_1 = d_2 = 0", "k = 2.4") sets the symbol; it does not define it.
    value = re.compile(r"^(?:[^=]*=\s*)?[-+\d.\s]*$")
    return [m.group(1) for s in T.text_sections() for m in pat.finditer(s.body) if not value.match(m.group(1))]


_TOKEN = re.compile(r"(?:\\[A-Za-z]+|[A-Za-z])_(?:\{[^{}]+\}|[A-Za-z0-9])")


def _meaning_clash(symbol: str, defs: list[str]):
    """Two definitions of one symbol that mean different things: their right-hand sides use
    different capacitance gradients (G_loc vs G_nl), or share no subscripted symbol at all."""
    for i, a in enumerate(defs):
        for b in defs[i + 1:]:
            ta = {T.canonical(x) for x in _TOKEN.findall(a)}
            tb = {T.canonical(x) for x in _TOKEN.findall(b)}
            gradients = [(x, y) for x in ta for y in tb if x[:2] == y[:2] == "G_" and x != y]
            if gradients:
                return a, b, f"{gradients[0][0]} vs {gradients[0][1]}"
            if ta and tb and not ta & tb:
                return a, b, f"{'/'.join(sorted(ta))} vs {'/'.join(sorted(tb))}"
    return None


def _condition_before(symbol: str) -> str | None:
    """The previous sentence when it states an inequality on the plain symbol (``$k \\gg ...$``)."""
    base = _split(symbol)[0]
    for sec in T.text_sections():
        for i, sentence in enumerate(sec.sentences):
            if re.search(re.escape(symbol).replace("_", r"_\{?"), sentence) and i:
                prev = sec.sentences[i - 1]
                if re.search(r"\$\s*" + re.escape(base) + r"\s*(?:\\gg|>|\\geq)", prev):
                    return prev
    return None


def _quote_definition(symbol: str, rhs: str) -> tuple:
    """A definition for the evidence: the equation number of a displayed one, else the formula."""
    tag = re.search(r"\\tag\{([^}]*)\}|\\quad\s*\((\d+[a-f]?)\)", rhs)
    if tag:
        return say(Tex(symbol), f" of Eq. ({tag.group(1) or tag.group(2)})")
    rhs = rhs.strip()
    return say(Tex(f"{symbol} = {rhs}")) if len(rhs) <= 80 else say(Tex(symbol), f" = (a {len(rhs)}-character formula)")


def _clash_reason(why: str) -> tuple:
    """'G_{loc} vs G_{nl}' as formulas."""
    return join([(Tex(x),) for x in why.split(" vs ")], " vs ")


def check_symbol(symbol: str):
    use = T.symbols()[symbol]
    defs = _definitions(symbol)
    clash = _meaning_clash(symbol, defs)
    if clash:
        a, b, why = clash
        base = _split(symbol)[0]
        subs = {re.sub(r"[^a-z]", "", x.split("_")[1]) for x in why.split(" vs ") if "_" in x}
        alt = [o for o in T.symbols() if _split(o)[0] == base and _split(o)[1] in subs and o != symbol]
        fix = say(Tex(alt[0]), " in the definition with ", _clash_reason(why)) if alt else "a distinct symbol for each meaning"
        return Evidence(ERRATUM, say(Tex(symbol), " is defined with different meanings: ",
                                     join([_quote_definition(symbol, d) for d in (a, b)], " and "),
                                     " (", _clash_reason(why), ")"), correction=fix)
    if use.uses == 1 and use.definition:
        base = _split(symbol)[0]
        mine = [d.strip() for d in defs]
        other = [d for d in _definitions(base) if any(m and m in d for m in mine)]
        if other:
            return Evidence(ERRATUM, say(Tex(f"{symbol} = {mine[0]}"), " is the definition of ", Tex(base), " (",
                                         Tex(f"{base} = {other[0].strip()}"), ") under another name, used once; the "
                                         "formula that follows uses ", Tex(base)), correction=Tex(base))
    near = _neighbours(symbol) if use.uses == 1 and not use.definition else []
    # The likeliest intended symbol: one used in the same section, then one whose subscript the misprint contains.
    near.sort(key=lambda n: (T.symbols()[n].section != use.section and not _used_in(n, use.section),
                             _split(n)[1] not in _split(symbol)[1]))
    if near:
        return Evidence(ERRATUM, say(Tex(symbol), f" is used once (Section {use.section}) and never defined; it is one "
                                     "edit away from ", join([(Tex(n), f" (used {T.symbols()[n].uses} times)") for n in near],
                                                             ", ")), correction=Tex(near[0]))
    if use.definition:
        return Evidence(HOLDS, say("defined: \"", T.quote(T.clip(use.definition, 160)), "\""))
    condition = _condition_before(symbol) if use.uses == 1 else None
    if condition:
        return Evidence(ERRATUM, say(Tex(symbol), " is used once and never defined; the sentence before states the "
                                     "condition on ", Tex(_split(symbol)[0]), ": \"", T.quote(T.clip(condition, 120)), "\""),
                        correction=Tex(_split(symbol)[0]))
    if use.uses >= 2:
        return Evidence(HOLDS, f"used {use.uses} times with one meaning, first in Section {use.section}; not a variant "
                               "of another symbol")
    return Evidence(UNDECIDABLE, f"used once (Section {use.section}) without an explicit definition; no symbol it "
                                 "could be a misprint of")
