"""Apply Alembic migrations programmatically (server start, ``gyrolab migrate``, tests)."""

from __future__ import annotations

from alembic import command
from alembic.config import Config

from app.paths import MIGRATIONS_DIR


def alembic_config(database_url: str | None = None) -> Config:
    from app.config import get_settings

    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS_DIR))
    config.set_main_option(
        "sqlalchemy.url", (database_url or get_settings().database_url).replace("%", "%%")
    )
    return config


def upgrade_to_head(database_url: str | None = None) -> None:
    command.upgrade(alembic_config(database_url), "head")
