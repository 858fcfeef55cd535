"""The parts both tracking layers are assembled from (docs/algorithms.md §7.5).

The local tracker (:class:`core.tracking.tracker.LocalTracker`, detections in)
and the fusion engine (:class:`core.fusion.engine.SessionEngine`, track lists
in) run the same pipeline over array state, one row per track:

============  ==========================================  ===============================
part          module                                      what both layers do with it
============  ==========================================  ===============================
predict       :mod:`core.pipeline.predict`                every row to the step's time in
                                                          one closed-form step (a zero
                                                          step is the estimate itself)
gate          :mod:`core.pipeline.gate`                   D = Δᵀ S⁻¹ Δ and log|S| of the
                                                          pairs (the score's and the
                                                          gate volume's inputs)
associate     :mod:`core.association` (tracker:           one method of §3 on the gated
              :mod:`core.tracking.associate`, engine:     pairs
              :mod:`core.fusion.associate`)
evidence      :mod:`core.pipeline.evidence`               hits and their ΔL, misses the
              (p: :mod:`core.pipeline.visibility`)        sensor should have seen (by
                                                          their gate, scored by p),
                                                          coverage, occlusion: the
                                                          :class:`core.lifecycle.Evidence`
life cycle    :mod:`core.lifecycle`                       :func:`~core.lifecycle.advance`
hand-over     :mod:`core.pipeline.handover`               newly confirmed rows matched to
                                                          phantoms (or a duplicate to its
                                                          established track); the fused
                                                          layer's to recently ended tracks,
                                                          on a unique match (§8.15)
rows          :mod:`core.pipeline.rows`                   numbers and lives of the rows:
                                                          start, keep, drop the terminated
============  ==========================================  ===============================

Every part is a function over arrays that returns new arrays (no part changes
its inputs in place), so an assembly's step is a transaction by construction.
"""
