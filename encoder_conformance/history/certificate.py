"""The one-page acceptance certificate: what goods-in files per delivered encoder.

``render_certificate`` is a pure function RunSummary -> HTML (unit-tested without a run); the page
carries its own print CSS (A4 portrait, one page) so any browser prints it as it is. Jinja2 renders it
(autoescaped: a device name is device data, not markup); it comes with pytest-html already.

PDF: WeasyPrint, when installed (``pip install -e ".[pdf]"``). Chosen because it renders the same
HTML and print CSS (``@page``) faithfully with a small pure-Python package (~5 MB of its own, plus
Pillow and fontTools, ~50 MB installed, which it brings itself now that the timing plots no longer
use matplotlib), while xhtml2pdf understands only a subset of CSS and pulls in ReportLab,
and no browser is on a station by default. WeasyPrint needs the Pango system library: present on
this project's machines (measured: import and one page 0.9 s on an idle 2-core machine, 2 s on a
loaded one), possibly missing on a fresh one. So the PDF is optional and never fails a run: without
WeasyPrint or Pango the HTML is the certificate and one note says why there is no PDF. It is an
extra, not a dependency, because its 1-2 s would lengthen every acceptance run (aimed at < 5 s) of a
station that only prints the HTML.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from jinja2 import Environment

from encoder_conformance.run_summary import RunSummary

HTML_NAME = "certificate.html"
PDF_NAME = "certificate.pdf"
FAILURES_SHOWN = 5  # a failed device's first failures fit on the page; the report has them all
MESSAGE_SHOWN = 120  # characters of a failure's first line (at most two lines of the table)

_TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{{ title }} {{ s.serial or "" }}</title>
<style>
@page { size: A4 portrait; margin: 12mm 14mm 12mm 18mm; }
* { box-sizing: border-box; }
body { font-family: "DejaVu Sans", Arial, Helvetica, sans-serif; font-size: 9.5pt; color: #111; margin: 0;
       max-width: 180mm; }
h1 { font-size: 17pt; margin: 0 0 1mm 0; }
.sub { color: #555; margin-bottom: 4mm; }
.verdict { font-size: 26pt; font-weight: bold; text-align: center; padding: 2mm; margin: 2mm 0 3mm 0;
           border: 1.2mm solid; border-radius: 2mm; }
.PASS { color: #1b6e20; border-color: #1b6e20; }
.FAIL { color: #b00020; border-color: #b00020; }
.WARN { color: #8a5a00; border-color: #c98a00; }
.NONE { color: #555; border-color: #777; }
.INC { color: #ad4e00; border-color: #ad4e00; }
table { border-collapse: collapse; width: 100%; margin-bottom: 3mm; }
table.areas { page-break-inside: avoid; }
table.failures td { font-size: 7.5pt; padding: 0.6mm 2mm; }
th, td { text-align: left; padding: 0.5mm 2mm; border-bottom: 0.2mm solid #bbb; vertical-align: top; }
th { background: #eee; }
td.k { width: 42mm; color: #444; }
td.n { text-align: right; width: 16mm; }
.mono { font-family: "DejaVu Sans Mono", Consolas, monospace; font-size: 8pt; overflow-wrap: anywhere; }
h2 { font-size: 11.5pt; margin: 3mm 0 1mm 0; }
.small { font-size: 8.5pt; color: #333; }
.sign { margin-top: 9mm; display: flex; gap: 12mm; }
.sign div { flex: 1; border-top: 0.3mm solid #000; padding-top: 1mm; font-size: 8.5pt; color: #444; }
@media screen { body { margin: 10mm auto; } }
@media print { .noprint { display: none; } }
</style></head><body>
<h1>{{ title }}</h1>
<div class="sub">CANopen encoder conformance suite (CiA 301 / 305 / 406) &middot; {{ kind_text }}</div>
<div class="verdict {{ css }}">{{ s.overall }}</div>
{% if s.could_not_test %}<p style="margin: 0 0 2mm 0"><b>Could not test:</b> {{ s.could_not_test }}</p>{% endif %}
<table>
<tr><td class="k">Serial number</td><td><b>{{ s.serial or "not read" }}</b></td></tr>
<tr><td class="k">Firmware / revision</td><td>{{ s.revision or "not read" }}</td></tr>
<tr><td class="k">Device</td><td>{{ ident("device name (1008h)") }}
 &middot; vendor-id {{ ident("vendor-id (1018h.1)") }}
 &middot; product code {{ ident("product code (1018h.2)") }}</td></tr>
<tr><td class="k">Device profile</td><td>{{ s.profile_id }}<br>
<span class="mono">sha256 {{ s.profile_sha256 }}</span></td></tr>
<tr><td class="k">Date</td><td>{{ date }} &middot; duration {{ "%.1f" % s.duration_s }} s</td></tr>
<tr><td class="k">Station / operator</td><td>{{ s.station or "-" }} / {{ s.operator or "-" }}</td></tr>
<tr><td class="k">Device given back</td><td>{{ restored }}</td></tr>
</table>
<h2>Verdict per area</h2>
<table class="areas">
<tr><th>Area</th><th>Verdict</th><th class="n">passed</th><th class="n">failed</th><th class="n">warnings</th>
<th class="n">skipped</th></tr>
{% for a in areas %}<tr><td>{{ a.area }}</td><td><b>{{ a.verdict }}</b></td><td class="n">{{ a.passed }}</td>
<td class="n">{{ a.failed }}</td><td class="n">{{ a.warnings }}</td><td class="n">{{ a.skipped }}</td></tr>
{% else %}<tr><td colspan="6">no test ran</td></tr>{% endfor %}
</table>
{% if failures %}<h2>Failures{% if more %} (first {{ failures|length }} of {{ failures|length + more }}){% endif %}</h2>
<table class="failures">{% for f in failures %}
<tr><td><span class="mono">{{ f.nodeid }}</span> {{ f.message }}</td></tr>
{% endfor %}</table>{% endif %}
<h2>Bus settings</h2>
<table class="small">{% for key, value in s.settings.items() %}<tr><td class="k">{{ key }}</td><td>{{ value }}</td></tr>
{% else %}<tr><td>-</td></tr>{% endfor %}</table>
<div class="small">Report folder: <span class="mono">{{ s.report_dir or "-" }}</span></div>
<div class="sign"><div>Date</div><div>Operator's signature</div></div>
</body></html>
"""

_ENV = Environment(autoescape=True, trim_blocks=True, lstrip_blocks=True)
_PAGE = _ENV.from_string(_TEMPLATE)


def _css(overall: str) -> str:
    return {"PASS": "PASS", "FAIL": "FAIL", "PASS WITH WARNINGS": "WARN", "INCOMPLETE": "INC"}.get(overall, "NONE")


def _date(started: str) -> str:
    try:
        return datetime.fromisoformat(started).strftime("%Y-%m-%d %H:%M:%S %z").strip()
    except ValueError:
        return started


def render_certificate(summary: RunSummary) -> str:
    """The certificate page of ``summary`` (HTML, print CSS for one A4 page)."""
    failed = summary.with_outcome("failed", "error")
    restored = {True: "yes, as found", False: "NO: see the report's restore section",
                None: "nothing to restore"}[summary.device_restored]
    title = "Acceptance certificate" if summary.kind == "accept" else "Conformance run certificate"
    return _PAGE.render(
        s=summary, title=title, css=_css(summary.overall), date=_date(summary.started), restored=restored,
        kind_text="acceptance check" if summary.kind == "accept" else "conformance run",
        areas=summary.areas(), failures=[_short(r) for r in failed[:FAILURES_SHOWN]],
        more=max(0, len(failed) - FAILURES_SHOWN), ident=lambda key: summary.identity.get(key, "-"))


def _short(result):  # noqa: ANN001 - TestResult in, a dict the template reads out
    first = result.message.strip().splitlines()[0] if result.message.strip() else ""
    shown = first[:MESSAGE_SHOWN] + ("..." if len(first) > MESSAGE_SHOWN else "")
    return {"nodeid": result.nodeid.removeprefix("suites/"), "message": shown}


@dataclass(frozen=True)
class CertificateFiles:
    html: Path
    pdf: Path | None
    pdf_note: str | None  # why there is no PDF


def write_pdf(html_text: str, path: Path) -> str | None:
    """Write the PDF with WeasyPrint; returns why not where it cannot (never raises)."""
    try:
        from weasyprint import HTML  # optional: pip install -e ".[pdf]"
    except ImportError:
        return "no PDF: WeasyPrint is not installed (pip install -e \".[pdf]\")"
    except OSError as exc:  # the Pango system library is missing
        return f"no PDF: WeasyPrint cannot load its system libraries (install Pango): {str(exc).splitlines()[0]}"
    try:
        HTML(string=html_text).write_pdf(path)
    except Exception as exc:  # a PDF is a convenience: nothing it raises may fail the run
        return f"no PDF: WeasyPrint failed: {type(exc).__name__}: {exc}"
    return None


def write_certificate(summary: RunSummary, folder: Path, pdf: bool = True) -> CertificateFiles:
    """certificate.html (and certificate.pdf where WeasyPrint works) in ``folder``. Raises OSError."""
    folder.mkdir(parents=True, exist_ok=True)
    text = render_certificate(summary)
    html_path = folder / HTML_NAME
    html_path.write_text(text, encoding="utf-8")
    note = write_pdf(text, folder / PDF_NAME) if pdf else "no PDF: not asked for"
    return CertificateFiles(html_path, None if note else folder / PDF_NAME, note)
