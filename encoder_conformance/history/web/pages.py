"""The page's HTML: Jinja2 templates with autoescape, so every value from the history (device names, messages,
paths, settings) is text, never markup; the plots come escaped from plot.py. No JavaScript: filters are a plain
GET form, so every view is a link the quality office can send."""

from __future__ import annotations

from typing import Any

from jinja2 import DictLoader, Environment

_BASE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{% block title %}{% endblock %} - run history</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 14px; margin: 0 1.5em 2em; color: #111; }
nav { padding: .6em 0; border-bottom: 1px solid #ccc; margin-bottom: 1em; }
nav a { margin-right: 1.2em; font-weight: bold; } nav .where { color: #666; float: right; font-size: 12px; }
table { border-collapse: collapse; margin: .4em 0 1em; } th, td { text-align: left; padding: 3px 9px;
  border-bottom: 1px solid #ddd; vertical-align: top; } th { background: #f0f0f0; }
.v { font-weight: bold; } .v-PASS { color: #2e7d32; } .v-FAIL { color: #c62828; }
.v-PASS-WITH-WARNINGS { color: #a06a00; } .v-COULD-NOT-TEST, .v-NOT-RUN { color: #666; }
.v-INTERNAL-ERROR { color: #6a1b9a; }
form.filters { display: flex; flex-wrap: wrap; gap: .5em 1em; align-items: end; background: #f7f7f7;
  padding: .7em; border: 1px solid #ddd; } form.filters label { display: flex; flex-direction: column;
  font-size: 12px; color: #444; } pre { white-space: pre-wrap; margin: .2em 0; font-size: 12.5px; }
.mono { font-family: "DejaVu Sans Mono", monospace; font-size: 12.5px; overflow-wrap: anywhere; }
.muted { color: #777; } td.date { white-space: nowrap; }
.error { border: 2px solid #c62828; padding: .8em; background: #fff3f3; }
.pages a, .pages span { margin-right: .8em; } svg.plot text { font-size: 12px; }
svg.plot text.head { font-weight: bold; } svg.plot text.onbar { fill: #fff; font-weight: bold; }
svg.plot text.muted { fill: #777; }
</style></head><body>
<nav><a href="/">Runs</a><a href="/stats">Pass rates</a><span class="where">{{ where }} (read-only)</span></nav>
{% block body %}{% endblock %}
</body></html>"""

_LIST = """{% extends "base" %}{% block title %}Runs{% endblock %}{% block body %}
<h1>Runs</h1>
<form class="filters" method="get" action="/">
<label>serial <input name="serial" value="{{ f.serial or '' }}" size="12"></label>
<label>station <select name="station"><option value="">any</option>{% for s in choices.station %}
<option{% if s == f.station %} selected{% endif %}>{{ s }}</option>{% endfor %}</select></label>
<label>profile <select name="profile"><option value="">any</option>{% for p in choices.profile %}
<option{% if p == f.profile %} selected{% endif %}>{{ p }}</option>{% endfor %}</select></label>
<label>kind <select name="kind"><option value="">any</option>{% for k in kinds %}
<option{% if k == f.kind %} selected{% endif %}>{{ k }}</option>{% endfor %}</select></label>
<label>verdict <select name="verdict"><option value="">any</option>{% for v in verdicts %}
<option{% if v == f.verdict %} selected{% endif %}>{{ v }}</option>{% endfor %}</select></label>
<label>from <input name="from" type="date" value="{{ f.given_from or '' }}"></label>
<label>until <input name="until" type="date" value="{{ f.given_until or '' }}"></label>
<button type="submit">Apply</button> <a href="/">clear</a>
</form>
<p id="count"><b>{{ "{:,}".format(total) }}</b> run(s) match{% if total %}; {{ first }}-{{ last }} shown, newest \
first{% endif %}. <a href="/stats?{{ f.query() }}">Pass rates of these runs</a></p>
<table id="runs"><tr><th>id</th><th>date</th><th>kind</th><th>profile</th><th>serial</th><th>revision</th>
<th>verdict</th><th>station</th><th>operator</th></tr>
{% for r in rows %}<tr><td><a href="/run/{{ r.id }}">{{ r.id }}</a></td>
<td class="date">{{ r.started[:16]|replace('T', ' ') }}</td>
<td>{{ r.kind }}</td><td>{{ r.profile_id }}</td>
<td>{% if r.serial %}<a href="/serial/{{ r.serial|urlencode }}">{{ r.serial }}</a>{% else %}-{% endif %}</td>
<td>{{ r.revision or "-" }}</td><td class="v v-{{ r.overall|replace(' ', '-') }}">{{ r.overall }}</td>
<td>{{ r.station or "-" }}</td><td>{{ r.operator or "-" }}</td></tr>
{% else %}<tr><td colspan="9" class="muted">no run matches these filters</td></tr>{% endfor %}</table>
<div class="pages">{% if page > 1 %}<a href="/?{{ f.query(page=page - 1) }}">&larr; newer</a>{% endif %}
<span>page {{ page }} of {{ pages }}</span>
{% if page < pages %}<a href="/?{{ f.query(page=page + 1) }}">older &rarr;</a>{% endif %}</div>
{% endblock %}"""

_RUN = """{% extends "base" %}{% block title %}Run {{ r.id }}{% endblock %}{% block body %}
<h1>Run {{ r.id }} ({{ r.kind }}): <span class="v v-{{ r.overall|replace(' ', '-') }}">{{ r.overall }}</span></h1>
{% if r.could_not_test %}<p><b>Could not test:</b> {{ r.could_not_test }}</p>{% endif %}
<h2>Identity</h2><table id="identity">
<tr><th>serial number</th><td>{% if r.serial %}<a href="/serial/{{ r.serial|urlencode }}">{{ r.serial }}</a>
 (timeline){% else %}not read{% endif %}</td></tr>
<tr><th>revision</th><td>{{ r.revision or "not read" }}</td></tr>
{% for key, value in identity.items() %}<tr><th>{{ key }}</th><td>{{ value }}</td></tr>{% endfor %}
<tr><th>profile</th><td>{{ r.profile_id }} <span class="mono">sha256 {{ r.profile_sha256 }}</span></td></tr>
<tr><th>started</th><td>{{ r.started }} ({{ "%.1f"|format(r.duration_s or 0) }} s)</td></tr>
<tr><th>station / operator</th><td>{{ r.station or "-" }} / {{ r.operator or "-" }}</td></tr>
<tr><th>exit code</th><td>{{ r.exit_code }}</td></tr><tr><th>device given back</th><td>{{ restored }}</td></tr>
</table>
<h2>Verdict per area</h2><table id="areas"><tr><th>area</th><th>verdict</th><th>passed</th><th>failed</th>
<th>warnings</th><th>skipped</th></tr>{% for a in areas %}<tr><td>{{ a.area }}</td>
<td class="v v-{{ a.verdict|replace(' ', '-') }}">{{ a.verdict }}</td><td>{{ a.passed }}</td><td>{{ a.failed }}</td>
<td>{{ a.warnings }}</td><td>{{ a.skipped }}</td></tr>{% else %}<tr><td colspan="6">no test ran</td></tr>
{% endfor %}</table>
<h2>Failures ({{ failures|length }})</h2>{% if failures %}<table id="failures"><tr><th>test</th>
<th>expected / observed</th></tr>{% for t in failures %}<tr><td class="mono">{{ t.nodeid }}<br>
<span class="muted">{{ t.outcome }}{% if t.source %}, {{ t.source }}{% endif %}</span></td>
<td><pre>{{ t.message }}</pre></td></tr>{% endfor %}</table>{% else %}<p>none</p>{% endif %}
<details><summary>all {{ results|length }} tests</summary><table>{% for t in results %}<tr>
<td class="mono">{{ t.nodeid }}</td><td>{{ t.outcome }}</td></tr>{% endfor %}</table></details>
<h2>Settings</h2><table id="settings">{% for key, value in settings.items() %}<tr><th>{{ key }}</th>
<td>{{ value }}</td></tr>{% else %}<tr><td>-</td></tr>{% endfor %}</table>
<h2>Files</h2><table id="files">
<tr><th>report folder</th><td class="mono">{{ r.report_dir or "-" }}</td><td>{% if report_link %}
<a href="{{ report_link }}">report.html</a>{% else %}<span class="muted">not reachable from this
computer</span>{% endif %}</td></tr>
<tr><th>certificate</th><td class="mono">{{ r.certificate or "none yet" }}</td><td>{% if certificate_link %}
<a href="{{ certificate_link }}">open</a>{% elif r.certificate %}<span class="muted">not reachable from this
computer</span>{% endif %}</td></tr></table>
{% endblock %}"""

_TIMELINE = """{% extends "base" %}{% block title %}Serial {{ serial }}{% endblock %}{% block body %}
<h1>Serial number {{ serial }}</h1><p>{{ runs|length }} run(s), oldest first.</p>
{{ plot }}
<table id="timeline"><tr><th>run</th><th>date</th><th>kind</th><th>profile</th><th>revision</th><th>verdict</th>
<th>station</th>{% for area in area_names %}<th>{{ area }}</th>{% endfor %}</tr>
{% for r in runs %}<tr><td><a href="/run/{{ r.id }}">{{ r.id }}</a></td>
<td class="date">{{ r.started[:16]|replace('T', ' ') }}</td>
<td>{{ r.kind }}</td><td>{{ r.profile_id }}</td><td>{{ r.revision or "-" }}</td>
<td class="v v-{{ r.overall|replace(' ', '-') }}">{{ r.overall }}</td><td>{{ r.station or "-" }}</td>
{% for area in area_names %}{% set v = areas[r.id].get(area) %}
<td class="v-{{ (v or '')|replace(' ', '-') }}">{{ v or "" }}</td>{% endfor %}</tr>{% endfor %}</table>
{% endblock %}"""

_STATS = """{% extends "base" %}{% block title %}Pass rates{% endblock %}{% block body %}
<h1>Pass rates</h1><p>{% if f.any %}Of the runs selected on <a href="/?{{ f.query() }}">this list</a>.
{% else %}Of every run in the history.{% endif %} A pass is PASS or PASS WITH WARNINGS; an area's count is the
runs in which it failed.</p>
{% for title, groups in sections %}<h2>Per {{ title }}</h2>{{ plots[loop.index0] }}
<table class="groups"><tr><th>{{ title }}</th><th>runs</th><th>passed</th><th>pass rate</th><th>fails most</th></tr>
{% for g in groups %}<tr><td>{{ g.name or "(none)" }}</td><td>{{ g.runs }}</td><td>{{ g.passed }}</td>
<td>{{ "%.0f"|format(100 * g.rate) }} %</td><td>{% for area, n in g.failing[:5] %}{{ area }} ({{ n }}){% if not
loop.last %}, {% endif %}{% else %}-{% endfor %}</td></tr>{% endfor %}</table>{% endfor %}
{% endblock %}"""

_ERROR = """{% extends "base" %}{% block title %}{{ title }}{% endblock %}{% block body %}
<h1>{{ title }}</h1><p class="error" id="message">{{ message }}</p><p><a href="/">All runs</a></p>
{% endblock %}"""

_ENV = Environment(loader=DictLoader({"base": _BASE, "list": _LIST, "run": _RUN, "timeline": _TIMELINE,
                                      "stats": _STATS, "error": _ERROR}), autoescape=True)


def render(name: str, **values: Any) -> str:
    """The page ``name`` (list, run, timeline, stats, error) with ``values``; ``where`` names the history."""
    return _ENV.get_template(name).render(**values)
