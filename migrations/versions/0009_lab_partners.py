"""lab partners: an assignment's group size, a session's partner code, session members

Revision ID: 0009
Revises: 0008
Create Date: 2026-11-22 22:20:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0009'
down_revision: str | None = '0008'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.add_column(sa.Column('group_size', sa.Integer(), nullable=False,
                                      server_default='1'))
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        batch_op.add_column(sa.Column('partner_code',
                                      sqlmodel.sql.sqltypes.AutoString(length=16),
                                      nullable=True))
        batch_op.create_unique_constraint('uq_lab_session_partner_code', ['partner_code'])
    op.create_table(
        'session_member',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('session_id', sa.Integer(), nullable=False),
        sa.Column('user_id', sa.Integer(), nullable=False),
        sa.Column('joined_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
        sa.ForeignKeyConstraint(['session_id'], ['lab_session.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['user_id'], ['user.id'], ondelete='CASCADE'),
        sa.PrimaryKeyConstraint('id'),
        sa.UniqueConstraint('session_id', 'user_id'),
    )
    with op.batch_alter_table('session_member', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_session_member_session_id'), ['session_id'])
        batch_op.create_index(batch_op.f('ix_session_member_user_id'), ['user_id'])


def downgrade() -> None:
    op.drop_table('session_member')
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        batch_op.drop_constraint('uq_lab_session_partner_code', type_='unique')
        batch_op.drop_column('partner_code')
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.drop_column('group_size')
