"""FastAPI dependencies (``Annotated`` aliases) shared by the routes."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from .config import Settings
from .state import AppState, ensure_state

__all__ = ["SettingsDep", "StateDep", "get_settings", "get_state"]


def get_state(request: Request) -> AppState:
    """The process's :class:`AppState` (built by the lifespan, or on first use without one)."""
    return ensure_state(request.app)


def get_settings(state: Annotated[AppState, Depends(get_state)]) -> Settings:
    """The service settings."""
    return state.settings


StateDep = Annotated[AppState, Depends(get_state)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
