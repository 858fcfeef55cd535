"""Output formats: one writer per format (:mod:`app.outputs.formats`)."""
