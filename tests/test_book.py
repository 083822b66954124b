"""The book builds (every page executed, warnings are errors) and renders offline.

One build per test session (module-scoped fixture, ~1-2 minutes).  The rendering checks open
built pages in headless Chromium with the network off (``unshare --net`` when available) and
read the DOM after scripts ran: MathJax must have typeset the math, and figures must load.
"""
from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("jupyter_book", reason="jupyter-book is not installed (pip install -e '.[book]')")

CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None)


@pytest.fixture(scope="module")
def built(tmp_path_factory, all_verdicts):
    """The book, built from the verdicts tests/test_verify.py checks (computed once per test run)."""
    from pfmdyn.book.records import VERDICTS_ENV, write_verdicts
    out = tmp_path_factory.mktemp("book")
    write_verdicts(out / "verdicts.json", all_verdicts)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pfmdyn.cli", "book", "--out", str(out)],
                          env={**os.environ, VERDICTS_ENV: str(out / "verdicts.json")},
                          capture_output=True, text=True, timeout=900)
    elapsed = time.perf_counter() - t0
    print(f"book build: {elapsed:.0f} s")
    return proc, out / "html", elapsed


def test_build_succeeds(built):
    proc, html_dir, _ = built
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-5000:]
    assert "open " in proc.stdout and str(html_dir / "index.html") in proc.stdout
    for page in ("index", "model", "elastic_contact", "frictionless", "pinned", "free_end",
                 "sliding_friction", "indentation", "torsion", "limits", "roots", "domains",
                 "deconvolution", "audit", "errata", "verdicts"):
        assert (html_dir / f"{page}.html").exists(), page


def test_the_build_prints_progress_not_warnings(built):
    """No kernel's start-up warning and no Python warning in what the build prints."""
    proc, _, _ = built
    text = proc.stdout + proc.stderr
    assert "WARNING" not in text and "Warning:" not in text, [l for l in text.splitlines() if "arning" in l][:5]


def test_tables_made_by_cells_render_as_tables(built):
    """A cell's Markdown table (calibrating, instruments) becomes an HTML table, not pipe text."""
    _, html_dir, _ = built
    for page in ("calibrating", "instruments"):
        text = (html_dir / f"{page}.html").read_text(encoding="utf-8")
        assert not re.search(r"<p>\s*\|", text), f"{page}: a table left as pipe text"
        assert "<table" in text, page


def test_no_remote_resources(built):
    """No page loads a script, stylesheet, font or image from the network."""
    _, html_dir, _ = built
    remote = re.compile(r"""(?:src|href)\s*=\s*["'](?:https?:)?//""", re.I)
    cdn = re.compile(r"cdn\.|jsdelivr|unpkg|googleapis|cdnjs", re.I)
    for page in html_dir.glob("*.html"):
        text = page.read_text(encoding="utf-8")
        for tag in re.findall(r"<(?:script|link|img)\b[^>]*>", text, re.I):
            assert not remote.search(tag), f"{page.name}: {tag}"
        assert not cdn.search(text), f"{page.name} names a CDN"


def test_numbers_come_from_the_verdicts(built):
    """The errata page states the erratum count of this build's verdicts."""
    import json
    _, html_dir, _ = built
    claims = json.loads((html_dir.parent / "verdicts.json").read_text())["claims"]
    n_errata = sum(c["verdict"] == "erratum" for c in claims)
    text = re.sub(r"<[^>]+>", "", (html_dir / "errata.html").read_text(encoding="utf-8"))
    assert f"{len(claims)} claims, {n_errata} are errata" in " ".join(text.split())
    assert text.count("As printed") == sum(c["verdict"] in ("erratum", "holds_up_to_sign_convention")
                                           and c["kind"] == "claim" for c in claims)


def _dump_dom(page: Path, tmp_path: Path, width: int = 1300) -> str:
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", f"--window-size={width},1000",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--no-first-run", f"--user-data-dir={tmp_path / 'chromium-profile'}",
           "--virtual-time-budget=15000", "--dump-dom", page.as_uri()]
    unshare = shutil.which("unshare")
    if unshare and hasattr(os, "geteuid") and os.geteuid() == 0:
        probe = subprocess.run([unshare, "--net", "true"], capture_output=True)
        if probe.returncode == 0:
            cmd = [unshare, "--net", *cmd]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def _visible_text(dom: str) -> str:
    dom = re.sub(r"<(script|style|mjx-assistive-mml)\b.*?</\1>", " ", dom, flags=re.S | re.I)
    return html.unescape(re.sub(r"<[^>]+>", " ", dom))


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
@pytest.mark.parametrize("page", ["limits", "domains", "deconvolution"])
def test_figures_load(built, tmp_path, page):
    _, html_dir, _ = built
    dom = _dump_dom(html_dir / f"{page}.html", tmp_path)
    sources = [s for s in re.findall(r"<img\b[^>]*\bsrc=\"([^\"]+)\"", dom) if s.endswith(".png")]
    assert sources, f"no figure on {page}.html"
    for src in sources:
        assert not src.startswith(("http:", "https:", "//"))
        assert (html_dir / src).resolve().is_file(), src


FAMILY_CHAPTERS = ("elastic_contact", "frictionless", "pinned", "free_end", "sliding_friction", "indentation", "torsion")

# Run in the page after MathJax has typeset it: the width of the text column and of every
# typeset equation, written into the DOM for --dump-dom to read.
_PROBE = """<script>
function pfmReport(data) {
  var out = document.createElement('pre'); out.id = 'pfm-probe';
  out.textContent = JSON.stringify(data); document.body.appendChild(out);
}
function pfmMeasure() {
  try {
    var col = document.querySelector('.bd-article') || document.querySelector('article') ||
              document.querySelector('main') || document.body;
    var right = col.getBoundingClientRect().right;
    var widths = Array.from(document.querySelectorAll('mjx-container mjx-math')).map(function (m) {
      return m.getBoundingClientRect().width; });
    var beyond = Array.from(document.querySelectorAll('mjx-container mjx-math')).filter(function (m) {
      return !m.closest('table'); }).map(function (m) { return m.getBoundingClientRect().right - right; });
    var tables = Array.from(document.querySelectorAll('table')).map(function (t) {
      return t.getBoundingClientRect().width; });
    pfmReport({column: col.getBoundingClientRect().width, widths: widths, beyond: beyond, tables: tables});
  } catch (e) { pfmReport({error: String(e)}); }
}
// MathJax's startup promise does not settle under --virtual-time-budget: wait instead until the
// number of typeset equations has been stable for one second (or ten seconds have passed).
function pfmWait(n, last, stable) {
  var count = document.querySelectorAll('mjx-container').length;
  stable = (count > 0 && count === last) ? stable + 1 : 0;
  if (stable >= 10 || n >= 100) { pfmMeasure(); }
  else { setTimeout(function () { pfmWait(n + 1, count, stable); }, 100); }
}
window.addEventListener('load', function () { pfmWait(0, -1, 0); });
</script>"""


def _probe(html_dir: Path, page: str, tmp_path: Path) -> tuple[str, dict]:
    import json
    src = (html_dir / f"{page}.html").read_text(encoding="utf-8")
    probe = html_dir / f"_probe_{page}.html"
    probe.write_text(src.replace("</body>", _PROBE + "</body>"), encoding="utf-8")
    try:
        dom = _dump_dom(probe, tmp_path, width=1300)
    finally:
        probe.unlink()
    m = re.search(r'<pre id="pfm-probe">(.*?)</pre>', dom, re.S)
    assert m, f"the width probe did not run on {page}.html"
    sizes = json.loads(html.unescape(m.group(1)))
    assert "error" not in sizes, sizes
    return dom, sizes


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
@pytest.mark.parametrize("page", ("errata", "limits", "audit", "verdicts") + FAMILY_CHAPTERS)
def test_equations_typeset_and_fit_the_column(built, tmp_path, page):
    """Offline, at 1300 px: MathJax output present, no raw TeX or SymPy powers left in the
    text, and no typeset equation or table wider than the text column (nothing cut off)."""
    _, html_dir, _ = built
    dom, sizes = _probe(html_dir, page, tmp_path)
    assert dom.count("<mjx-container") >= 1, f"MathJax did not typeset {page}.html"
    # Source code shown in the page (<pre> blocks) may contain ** legitimately; prose may not.
    text = _visible_text(re.sub(r"<pre\b.*?</pre>", " ", dom, flags=re.S))
    for raw in ("$$", r"\[", r"\(", r"\frac", r"\begin{aligned}", "**"):
        assert raw not in text, f"raw {raw!r} left in the text of {page}.html"
    too_wide = [round(w) for w in sizes["widths"] if w > sizes["column"] + 1]
    assert not too_wide, f"{page}.html: equations {too_wide} px wide in a {sizes['column']:.0f} px column"
    cut = [round(b) for b in sizes["beyond"] if b > 1]
    assert not cut, f"{page}.html: equations ending {cut} px beyond the column's right edge (tables scroll)"
    if page == "errata":    # set in result boxes: a reader's browser found six of 545-693 px too wide there
        assert max(sizes["widths"]) <= 560, sorted(round(w) for w in sizes["widths"])[-6:]
    wide_tables = [round(w) for w in sizes["tables"] if w > sizes["column"] + 1]
    assert not wide_tables, f"{page}.html: tables {wide_tables} px wide in a {sizes['column']:.0f} px column"
