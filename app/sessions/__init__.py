"""Live sessions: the registry, one session's engine and subscribers, its log, the translation."""
