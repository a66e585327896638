"""bigint simulator seed (62-bit seeds overflow PostgreSQL's INTEGER)

Revision ID: 0005
Revises: 0004
Create Date: 2026-11-21 15:10:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op


revision: str = '0005'
down_revision: str | None = '0004'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    # SQLite's INTEGER is already 64-bit; rebuilding the table there would gain nothing.
    if op.get_bind().dialect.name != "sqlite":
        op.alter_column('lab_session', 'sim_seed', type_=sa.BigInteger(),
                        existing_type=sa.Integer(), existing_nullable=False)


def downgrade() -> None:
    if op.get_bind().dialect.name != "sqlite":
        op.alter_column('lab_session', 'sim_seed', type_=sa.Integer(),
                        existing_type=sa.BigInteger(), existing_nullable=False)
