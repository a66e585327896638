"""real instruments: the gyro's case temperature beside its samples (the bridge sends it
when the instrument reports it)

Revision ID: 0013
Revises: 0012
Create Date: 2026-11-23 12:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op


revision: str = '0013'
down_revision: str | None = '0012'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('sample_chunk', schema=None) as batch_op:
        batch_op.add_column(sa.Column('temperatures', sa.LargeBinary(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table('sample_chunk', schema=None) as batch_op:
        batch_op.drop_column('temperatures')
