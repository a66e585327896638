"""Errors in the input that a student can understand and fix."""

from __future__ import annotations


class GyroInputError(ValueError):
    """Bad or insufficient readings.  ``key`` names the message for translation.

    ``str(error)`` is a complete English sentence; ``params`` fill the translated text.
    """

    def __init__(self, key: str, message: str, **params: object) -> None:
        super().__init__(message)
        self.key = key
        self.params = params
