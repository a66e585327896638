"""The accounts API's response models: a token, the caller, a new password."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field


class TokenOut(BaseModel):
    access_token: str
    token_type: Literal["bearer"] = "bearer"
    expires_in: int = Field(description="seconds")


class MeOut(BaseModel):
    id: int
    username: str
    display_name: str
    role: str
    language: str | None


class NewPasswordOut(BaseModel):
    username: str
    initial_password: str = Field(description="one-time: the user must change it at log-in")
