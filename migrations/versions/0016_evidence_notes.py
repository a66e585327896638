"""a teacher marks a data-evidence finding as seen, with a note

Revision ID: 0016
Revises: 0015
Create Date: 2026-11-25 12:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0016'
down_revision: str | None = '0015'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        'evidence_note',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('session_id', sa.Integer(), nullable=False),
        sa.Column('check', sqlmodel.sql.sqltypes.AutoString(length=16), nullable=False),
        sa.Column('part', sqlmodel.sql.sqltypes.AutoString(length=16), nullable=False),
        sa.Column('note', sqlmodel.sql.sqltypes.AutoString(length=2000), nullable=False),
        sa.Column('teacher_id', sa.Integer(), nullable=True),
        sa.Column('seen_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
        sa.ForeignKeyConstraint(['session_id'], ['lab_session.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['teacher_id'], ['user.id'], ondelete='SET NULL'),
        sa.PrimaryKeyConstraint('id'),
        sa.UniqueConstraint('session_id', 'check', 'part'),
    )
    with op.batch_alter_table('evidence_note', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_evidence_note_session_id'), ['session_id'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('evidence_note', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_evidence_note_session_id'))
    op.drop_table('evidence_note')
