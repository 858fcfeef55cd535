"""Track-to-track fusion ([T2T] Fig 1-2, ALGORITHMS.md §6)."""
