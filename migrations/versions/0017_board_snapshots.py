"""the class board's snapshots, kept with the assignment

Revision ID: 0017
Revises: 0016
Create Date: 2026-11-25 13:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0017'
down_revision: str | None = '0016'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        'board_snapshot',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('assignment_id', sa.Integer(), nullable=False),
        sa.Column('teacher_id', sa.Integer(), nullable=True),
        sa.Column('created_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
        sa.Column('data', sqlmodel.sql.sqltypes.AutoString(length=2000000), nullable=False),
        sa.ForeignKeyConstraint(['assignment_id'], ['assignment.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['teacher_id'], ['user.id'], ondelete='SET NULL'),
        sa.PrimaryKeyConstraint('id'),
    )
    with op.batch_alter_table('board_snapshot', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_board_snapshot_assignment_id'), ['assignment_id'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('board_snapshot', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_board_snapshot_assignment_id'))
    op.drop_table('board_snapshot')
