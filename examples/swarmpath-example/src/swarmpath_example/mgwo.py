"""mGWO: the Grey Wolf Optimizer with an exponentially decaying control parameter.

N. Mittal, U. Singh and B. S. Sohi, "Modified Grey Wolf Optimizer for Global Engineering
Optimization", Applied Computational Intelligence and Soft Computing, vol. 2016, Article ID
7950348, doi:10.1155/2016/7950348.

GWO's control parameter a falls linearly from 2 to 0, so half of the iterations explore
(|A| > 1 is possible) and half exploit. mGWO keeps every other equation of GWO and lets a decay
as a = 2 (1 - t^2 / T^2) (its eq. 7), t the iteration counter from 0 and T the iterations: a stays
above 1 for 1/sqrt(2) = 71 % of the run, so it explores longer. Implemented on swarmpath's GWO
(the authors' leader update, GWO.m's counter t = 0..T-1): only :meth:`control` differs.
"""

from __future__ import annotations

from swarmpath.optimizers import register
from swarmpath.optimizers.gwo import GWO


@register
class MGWO(GWO):
    name = "mGWO"
    summary = "modified GWO (Mittal et al. 2016): a = 2(1 - t^2/T^2)"
    reference = ("Mittal, Singh & Sohi, Appl. Comput. Intell. Soft Comput. 2016, 7950348, "
                 "eq. 7")

    def control(self) -> float:
        done = (self.t - 1) / self.T  # GWO.m's l / Max_iter, l = 0..T-1
        return float(self.p["a_max"]) * (1.0 - done * done)
