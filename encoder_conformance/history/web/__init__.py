"""``encoder-conformance history serve``: the history as a read-only web page for the quality office.

params.py: the page's filters from the query string (a bad one is a 400 with a clear message); queries.py: the
SELECTs (paginated, on indexed columns); plot.py: the inline SVG plots; pages.py: the HTML (Jinja2, every value
escaped); app.py: the routes (Starlette); server.py: listening (uvicorn, loopback unless told otherwise).
"""
