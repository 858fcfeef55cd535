"""The wire contract: pydantic v2 models of every request, response and message."""
