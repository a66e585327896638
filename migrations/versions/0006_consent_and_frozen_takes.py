"""who created an account, course join codes, frozen (submitted) takes, request windows
for cookie-authenticated API calls

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-22 13:20:00
"""
import secrets
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0006'
down_revision: str | None = '0005'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JOIN_ALPHABET = "ABCDEFGHJKLMNPQRSTUVWXYZ23456789"


def upgrade() -> None:
    with op.batch_alter_table('user', schema=None) as batch_op:
        batch_op.add_column(sa.Column('created_by_id', sa.Integer(), nullable=True))
        batch_op.create_foreign_key('fk_user_created_by_id_user', 'user', ['created_by_id'],
                                    ['id'], ondelete='SET NULL')
    with op.batch_alter_table('course', schema=None) as batch_op:
        batch_op.add_column(sa.Column('join_code', sqlmodel.sql.sqltypes.AutoString(length=16),
                                      nullable=True))
    with op.batch_alter_table('take', schema=None) as batch_op:
        batch_op.add_column(sa.Column('frozen', sa.Boolean(), nullable=False,
                                      server_default=sa.false()))

    with op.batch_alter_table('auth_session', schema=None) as batch_op:
        batch_op.add_column(sa.Column('window_start', sqlmodel.sql.sqltypes.UTCDateTime(),
                                      nullable=True))
        batch_op.add_column(sa.Column('window_count', sa.Integer(), nullable=False,
                                      server_default='0'))

    bind = op.get_bind()
    for (course_id,) in bind.execute(sa.text('SELECT id FROM course')).all():
        code = "".join(secrets.choice(JOIN_ALPHABET) for _ in range(8))
        bind.execute(sa.text('UPDATE course SET join_code = :code WHERE id = :id'),
                     {"code": code, "id": course_id})
    # Takes that an attempt refers to are frozen: submitted data never changes.
    for (take_ids,) in bind.execute(sa.text('SELECT take_ids FROM attempt')).all():
        ids = [int(i) for i in (take_ids or "").split(",") if i.strip()]
        if ids:
            bind.execute(sa.text('UPDATE take SET frozen = :yes WHERE id IN :ids')
                         .bindparams(sa.bindparam('ids', expanding=True)),
                         {"yes": True, "ids": ids})
    with op.batch_alter_table('course', schema=None) as batch_op:
        batch_op.alter_column('join_code', existing_type=sqlmodel.sql.sqltypes.AutoString(length=16),
                              nullable=False)
        batch_op.create_index(batch_op.f('ix_course_join_code'), ['join_code'], unique=True)


def downgrade() -> None:
    with op.batch_alter_table('auth_session', schema=None) as batch_op:
        batch_op.drop_column('window_count')
        batch_op.drop_column('window_start')
    with op.batch_alter_table('course', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_course_join_code'))
        batch_op.drop_column('join_code')
    with op.batch_alter_table('take', schema=None) as batch_op:
        batch_op.drop_column('frozen')
    with op.batch_alter_table('user', schema=None) as batch_op:
        batch_op.drop_constraint('fk_user_created_by_id_user', type_='foreignkey')
        batch_op.drop_column('created_by_id')
