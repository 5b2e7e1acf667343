"""Device profiles: the YAML model of what an encoder should be (objects, defaults, timing, quirks), its loader
with ``extends:``, value domains, and the EDS importer (``eds/``)."""
