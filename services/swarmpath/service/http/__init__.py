"""The coordinator's HTTP side: the FastAPI application factory (:func:`create_app`), its
dependencies and middleware, and one router module per resource under ``routes/``. Routes are
thin: they validate, call the coordinator or store, and shape the answer."""

from swarmpath.service.http.app import create_app

__all__ = ["create_app"]
