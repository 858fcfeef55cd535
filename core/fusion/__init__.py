"""Track-to-track fusion ([T2T] Fig 1-2, docs/algorithms.md §6)."""
