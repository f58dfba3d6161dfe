"""The distributed experiment service: protocol models, the SQLite job store and the MCAP recorder.

Everything in this package below the network layer is plain Python, testable without Zenoh or HTTP:

* :mod:`swarmpath.service.protocol` - pydantic models of every message and the key expressions;
* :mod:`swarmpath.service.schemas` - JSON Schema export to ``schemas/`` (``python -m ...``);
* :mod:`swarmpath.service.store` - the durable job queue (jobs, cells, leases, results);
* :mod:`swarmpath.service.recorder` - one MCAP file per job, rebuilt from the store after a crash;
* :mod:`swarmpath.service.foxglove` - Foxglove well-known JSON schemas and message builders.
"""
