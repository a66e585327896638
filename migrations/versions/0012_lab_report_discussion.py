"""lab reports: the student's own discussion, a draft on the session and frozen with each
attempt

Revision ID: 0012
Revises: 0011
Create Date: 2026-11-23 09:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0012'
down_revision: str | None = '0011'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    for table in ('lab_session', 'attempt'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.add_column(sa.Column(
                'discussion', sqlmodel.sql.sqltypes.AutoString(length=20000),
                nullable=False, server_default='',
            ))


def downgrade() -> None:
    for table in ('attempt', 'lab_session'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.drop_column('discussion')
