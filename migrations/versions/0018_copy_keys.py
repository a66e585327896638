"""copy keys of submitted attempts and of uploaded earlier years' readings

Revision ID: 0018
Revises: 0017
Create Date: 2026-11-25 15:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0018'
down_revision: str | None = '0017'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        'reading_archive',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('teacher_id', sa.Integer(), nullable=False),
        sa.Column('name', sqlmodel.sql.sqltypes.AutoString(length=200), nullable=False),
        sa.Column('groups', sa.Integer(), nullable=False),
        sa.Column('uploaded_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
        sa.ForeignKeyConstraint(['teacher_id'], ['user.id'], ondelete='CASCADE'),
        sa.PrimaryKeyConstraint('id'),
    )
    with op.batch_alter_table('reading_archive', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_reading_archive_teacher_id'), ['teacher_id'], unique=False)
    op.create_table(
        'copy_key',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('key', sqlmodel.sql.sqltypes.AutoString(length=72), nullable=False),
        sa.Column('part', sqlmodel.sql.sqltypes.AutoString(length=8), nullable=False),
        sa.Column('attempt_id', sa.Integer(), nullable=True),
        sa.Column('archive_id', sa.Integer(), nullable=True),
        sa.Column('label', sqlmodel.sql.sqltypes.AutoString(length=200), nullable=False),
        sa.Column('attempt', sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(['attempt_id'], ['attempt.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['archive_id'], ['reading_archive.id'], ondelete='CASCADE'),
        sa.PrimaryKeyConstraint('id'),
    )
    with op.batch_alter_table('copy_key', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_copy_key_key'), ['key'], unique=False)
        batch_op.create_index(batch_op.f('ix_copy_key_attempt_id'), ['attempt_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_copy_key_archive_id'), ['archive_id'], unique=False)
    with op.batch_alter_table('attempt', schema=None) as batch_op:
        # existing attempts are indexed when the app starts (app/lab/copy_index.py)
        batch_op.add_column(
            sa.Column('copy_indexed', sa.Boolean(), nullable=False, server_default=sa.false())
        )


def downgrade() -> None:
    with op.batch_alter_table('attempt', schema=None) as batch_op:
        batch_op.drop_column('copy_indexed')
    with op.batch_alter_table('copy_key', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_copy_key_archive_id'))
        batch_op.drop_index(batch_op.f('ix_copy_key_attempt_id'))
        batch_op.drop_index(batch_op.f('ix_copy_key_key'))
    op.drop_table('copy_key')
    with op.batch_alter_table('reading_archive', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_reading_archive_teacher_id'))
    op.drop_table('reading_archive')
