"""The coordinator's web dashboard: page data (aggregates, map scenes, the live job list) and
the static pages and scripts in ``static/`` (shipped as package data, nothing from a CDN)."""
