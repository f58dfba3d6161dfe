"""The evidence layer: what a study's numbers mean, on top of the pure core.

Statistics of runs (:mod:`.stats`), comparisons between algorithms and planners (:mod:`.compare`,
:mod:`.compare_maps`), the papers' tables (:mod:`.report`), reproduction of the seed papers
(:mod:`.reference`, :mod:`.reproduction`), the origin-bias audit (:mod:`.audit`), figures
(:mod:`.plots`, :mod:`.cdplot`) and exports (:mod:`.exports`, :mod:`.ioh`, :mod:`.legend`).
Pure functions over results, except the figure and export writers; no network, no global state.
"""
