"""LTI 1.3: platforms, signing keys, handshake values, contexts, resource links, grade posts

Revision ID: 0011
Revises: 0010
Create Date: 2026-11-23 02:40:08.815913
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0011'
down_revision: str | None = '0010'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table('lti_key',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('kid', sqlmodel.sql.sqltypes.AutoString(length=64), nullable=False),
    sa.Column('private_pem', sqlmodel.sql.sqltypes.AutoString(length=8000), nullable=False),
    sa.Column('public_jwk', sqlmodel.sql.sqltypes.AutoString(length=4000), nullable=False),
    sa.Column('created_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.Column('retired_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=True),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('kid')
    )
    op.create_table('lti_launch_value',
    sa.Column('key', sqlmodel.sql.sqltypes.AutoString(length=200), nullable=False),
    sa.Column('value', sqlmodel.sql.sqltypes.AutoString(length=200000), nullable=False),
    sa.Column('expires_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.PrimaryKeyConstraint('key')
    )
    with op.batch_alter_table('lti_launch_value', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_lti_launch_value_expires_at'), ['expires_at'], unique=False)

    op.create_table('lti_platform',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sqlmodel.sql.sqltypes.AutoString(length=200), nullable=False),
    sa.Column('issuer', sqlmodel.sql.sqltypes.AutoString(length=500), nullable=False),
    sa.Column('client_id', sqlmodel.sql.sqltypes.AutoString(length=255), nullable=False),
    sa.Column('auth_login_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=False),
    sa.Column('auth_token_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=False),
    sa.Column('auth_audience', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=True),
    sa.Column('key_set_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=False),
    sa.Column('deployment_ids', sqlmodel.sql.sqltypes.AutoString(length=4000), nullable=False),
    sa.Column('registered_by', sqlmodel.sql.sqltypes.AutoString(length=16), nullable=False),
    sa.Column('created_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('issuer', 'client_id')
    )
    with op.batch_alter_table('lti_platform', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_lti_platform_issuer'), ['issuer'], unique=False)

    op.create_table('lti_context',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('platform_id', sa.Integer(), nullable=False),
    sa.Column('context_id', sqlmodel.sql.sqltypes.AutoString(length=255), nullable=False),
    sa.Column('course_id', sa.Integer(), nullable=False),
    sa.Column('title', sqlmodel.sql.sqltypes.AutoString(length=255), nullable=False),
    sa.Column('memberships_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=True),
    sa.Column('lineitems_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=True),
    sa.Column('ags_scopes', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=False),
    sa.Column('roster_synced_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=True),
    sa.Column('roster_problem', sqlmodel.sql.sqltypes.AutoString(length=500), nullable=True),
    sa.ForeignKeyConstraint(['course_id'], ['course.id'], ondelete='CASCADE'),
    sa.ForeignKeyConstraint(['platform_id'], ['lti_platform.id'], ondelete='CASCADE'),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('platform_id', 'context_id')
    )
    with op.batch_alter_table('lti_context', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_lti_context_course_id'), ['course_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_context_platform_id'), ['platform_id'], unique=False)

    op.create_table('lti_resource_link',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('platform_id', sa.Integer(), nullable=False),
    sa.Column('resource_link_id', sqlmodel.sql.sqltypes.AutoString(length=255), nullable=False),
    sa.Column('context_row_id', sa.Integer(), nullable=False),
    sa.Column('assignment_id', sa.Integer(), nullable=True),
    sa.Column('lineitem_url', sqlmodel.sql.sqltypes.AutoString(length=1000), nullable=True),
    sa.Column('created_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.ForeignKeyConstraint(['assignment_id'], ['assignment.id'], ondelete='CASCADE'),
    sa.ForeignKeyConstraint(['context_row_id'], ['lti_context.id'], ondelete='CASCADE'),
    sa.ForeignKeyConstraint(['platform_id'], ['lti_platform.id'], ondelete='CASCADE'),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('platform_id', 'resource_link_id')
    )
    with op.batch_alter_table('lti_resource_link', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_lti_resource_link_assignment_id'), ['assignment_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_resource_link_context_row_id'), ['context_row_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_resource_link_platform_id'), ['platform_id'], unique=False)

    op.create_table('lti_grade_post',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('attempt_id', sa.Integer(), nullable=False),
    sa.Column('student_id', sa.Integer(), nullable=False),
    sa.Column('link_id', sa.Integer(), nullable=False),
    sa.Column('score', sa.Float(), nullable=False),
    sa.Column('maximum', sa.Float(), nullable=False),
    sa.Column('comment', sqlmodel.sql.sqltypes.AutoString(length=20000), nullable=False),
    sa.Column('status', sqlmodel.sql.sqltypes.AutoString(length=8), nullable=False),
    sa.Column('tries', sa.Integer(), nullable=False),
    sa.Column('last_error', sqlmodel.sql.sqltypes.AutoString(length=500), nullable=True),
    sa.Column('next_try_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.Column('created_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=False),
    sa.Column('sent_at', sqlmodel.sql.sqltypes.UTCDateTime(), nullable=True),
    sa.ForeignKeyConstraint(['attempt_id'], ['attempt.id'], ondelete='CASCADE'),
    sa.ForeignKeyConstraint(['link_id'], ['lti_resource_link.id'], ondelete='CASCADE'),
    sa.ForeignKeyConstraint(['student_id'], ['user.id'], ondelete='CASCADE'),
    sa.PrimaryKeyConstraint('id')
    )
    with op.batch_alter_table('lti_grade_post', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_lti_grade_post_attempt_id'), ['attempt_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_grade_post_link_id'), ['link_id'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_grade_post_next_try_at'), ['next_try_at'], unique=False)
        batch_op.create_index(batch_op.f('ix_lti_grade_post_student_id'), ['student_id'], unique=False)



def downgrade() -> None:
    with op.batch_alter_table('lti_grade_post', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_lti_grade_post_student_id'))
        batch_op.drop_index(batch_op.f('ix_lti_grade_post_next_try_at'))
        batch_op.drop_index(batch_op.f('ix_lti_grade_post_link_id'))
        batch_op.drop_index(batch_op.f('ix_lti_grade_post_attempt_id'))

    op.drop_table('lti_grade_post')
    with op.batch_alter_table('lti_resource_link', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_lti_resource_link_platform_id'))
        batch_op.drop_index(batch_op.f('ix_lti_resource_link_context_row_id'))
        batch_op.drop_index(batch_op.f('ix_lti_resource_link_assignment_id'))

    op.drop_table('lti_resource_link')
    with op.batch_alter_table('lti_context', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_lti_context_platform_id'))
        batch_op.drop_index(batch_op.f('ix_lti_context_course_id'))

    op.drop_table('lti_context')
    with op.batch_alter_table('lti_platform', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_lti_platform_issuer'))

    op.drop_table('lti_platform')
    with op.batch_alter_table('lti_launch_value', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_lti_launch_value_expires_at'))

    op.drop_table('lti_launch_value')
    op.drop_table('lti_key')
