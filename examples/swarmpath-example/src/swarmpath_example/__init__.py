"""An example swarmpath plugin (examples/swarmpath-example/README.md).

* :class:`~swarmpath_example.mgwo.MGWO`, the modified Grey Wolf Optimizer of Mittal, Singh &
  Sohi (2016), registered as ``mGWO``;
* :data:`~swarmpath_example.spring.SPRING`, the tension/compression spring design problem
  (Belegundu 1982; Arora 1989), registered as ``spring-design``.

Installed, swarmpath finds both through this package's entry points; without installing,
``swarmpath bench --plugin swarmpath_example ...`` loads them (the modules register themselves).
"""

from swarmpath_example.mgwo import MGWO
from swarmpath_example.spring import SPRING

__all__ = ["MGWO", "SPRING"]
