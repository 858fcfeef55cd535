"""The papers' experiments, reproduced on the core (EVALUATION.md, issue 7).

One module per experiment, each a function of sizes and seeds returning
plain result data (numpy arrays in frozen dataclasses), so that tests run
them reduced and :mod:`evaluation.figures` draws them full size:

- :mod:`~evaluation.four_targets` — [T2T] Fig 4, false decisions vs λ / γ;
- :mod:`~evaluation.two_class` — [T2T] Fig 6, distance only vs distance + class;
- :mod:`~evaluation.aircraft` — [MTT] Fig 12–15, behaviours, credal vs Bayesian classification;
- :mod:`~evaluation.pedestrian` — [MTT] Fig 20–23, discounting for changing classes;
- :mod:`~evaluation.units` — is the "parameterless" ``hachour`` unit-free?
- :mod:`~evaluation.pairing` — the track-to-track problems and their false decision rate;
- :mod:`~evaluation.close_pair` — [MTT] Fig 16, false assignments of two close targets;
- :mod:`~evaluation.crossing` — [MTT] Fig 17–18, a fighter crosses an unknown aircraft;
- :mod:`~evaluation.road_four` — [DH] Fig 1–5, RMS errors per vehicle vs cheap JPDA in clutter;
- :mod:`~evaluation.accelerating` — [HZ] Fig 5, modified distance and termination;
- :mod:`~evaluation.overtaking` — [HZ] Fig 6, phantoms through a blind zone;
- :mod:`~evaluation.scenes` — [MTT] Fig 4–5, 10–11, 19, the scenes tracked;
- :mod:`~evaluation.peers` — issue 13, ``bench/peers.py``'s Stone Soup side-by-side over seeds;
- :mod:`~evaluation.tracking` — running the local tracker over a scenario (shared);
- :mod:`~evaluation.intervals` — 95 % intervals, bootstrap and paired tests (shared).

- :mod:`~evaluation.catalogue` — the names of the figures (no plotting code);
- :mod:`~evaluation.figures` — draws them (matplotlib: the ``figures`` extra).

The package depends on :mod:`core`, never the other way. Nothing is imported
here, so that ``import evaluation.catalogue`` (the CLI) stays cheap: import
each experiment from its module.
"""
