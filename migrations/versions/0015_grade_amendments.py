"""released grades can be amended with a reason; the history of each change is kept

Revision ID: 0015
Revises: 0014
Create Date: 2026-11-25 10:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0015'
down_revision: str | None = '0014'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        'grade_amendment',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('attempt_id', sa.Integer(), nullable=False),
        sa.Column('teacher_id', sa.Integer(), nullable=True),
        sa.Column('amended_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
        sa.Column('reason', sqlmodel.sql.sqltypes.AutoString(length=2000), nullable=False),
        sa.Column('points_before', sa.Float(), nullable=True),
        sa.Column('points_after', sa.Float(), nullable=True),
        sa.Column('letter_before', sqlmodel.sql.sqltypes.AutoString(length=32), nullable=True),
        sa.Column('letter_after', sqlmodel.sql.sqltypes.AutoString(length=32), nullable=True),
        sa.Column('feedback_before', sqlmodel.sql.sqltypes.AutoString(length=20000), nullable=False),
        sa.ForeignKeyConstraint(['attempt_id'], ['attempt.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['teacher_id'], ['user.id'], ondelete='SET NULL'),
        sa.PrimaryKeyConstraint('id'),
    )
    with op.batch_alter_table('grade_amendment', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_grade_amendment_attempt_id'), ['attempt_id'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('grade_amendment', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_grade_amendment_attempt_id'))
    op.drop_table('grade_amendment')
