"""the grading desk: feedback, points, rubric scores and release per attempt (moved from the
session); the assignment's maximum points and rubric; per-student due-date extensions; the
course's time zone; a take's trimmed start

Revision ID: 0008
Revises: 0007
Create Date: 2026-11-22 22:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0008'
down_revision: str | None = '0007'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

TEXT = sqlmodel.sql.sqltypes.AutoString
WHEN = sqlmodel.sql.sqltypes.UTCDateTime


def upgrade() -> None:
    with op.batch_alter_table('course', schema=None) as batch_op:
        batch_op.add_column(sa.Column('timezone', TEXT(length=64), nullable=True))
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.add_column(sa.Column('max_points', sa.Float(), nullable=False,
                                      server_default='100'))
        batch_op.add_column(sa.Column('rubric', TEXT(length=20000), nullable=False,
                                      server_default='[]'))
    with op.batch_alter_table('take', schema=None) as batch_op:
        batch_op.add_column(sa.Column('trim_start', sa.Integer(), nullable=False,
                                      server_default='0'))
    with op.batch_alter_table('attempt', schema=None) as batch_op:
        batch_op.add_column(sa.Column('feedback', TEXT(length=20000), nullable=False,
                                      server_default=''))
        batch_op.add_column(sa.Column('feedback_positions', TEXT(length=20000), nullable=False,
                                      server_default='{}'))
        batch_op.add_column(sa.Column('points', sa.Float(), nullable=True))
        batch_op.add_column(sa.Column('rubric_points', TEXT(length=4000), nullable=False,
                                      server_default='{}'))
        batch_op.add_column(sa.Column('letter', TEXT(length=32), nullable=True))
        for name in ('returned_at', 'released_at', 'seen_at'):
            batch_op.add_column(sa.Column(name, WHEN(), nullable=True))
    op.create_table(
        'extension',
        sa.Column('id', sa.Integer(), nullable=False),
        sa.Column('assignment_id', sa.Integer(), nullable=False),
        sa.Column('student_id', sa.Integer(), nullable=False),
        sa.Column('due_at', WHEN(), nullable=False),
        sa.Column('created_at', WHEN(), nullable=False),
        sa.ForeignKeyConstraint(['assignment_id'], ['assignment.id'], ondelete='CASCADE'),
        sa.ForeignKeyConstraint(['student_id'], ['user.id'], ondelete='CASCADE'),
        sa.PrimaryKeyConstraint('id'),
        sa.UniqueConstraint('assignment_id', 'student_id'),
    )
    with op.batch_alter_table('extension', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_extension_assignment_id'), ['assignment_id'])
        batch_op.create_index(batch_op.f('ix_extension_student_id'), ['student_id'])
    # the review written so far belongs to each session's latest attempt; a letter grade
    # that is a number becomes points
    op.execute(
        """
        UPDATE attempt SET
          feedback = (SELECT s.feedback FROM lab_session s WHERE s.id = attempt.session_id),
          feedback_positions = (SELECT s.feedback_positions FROM lab_session s
                                WHERE s.id = attempt.session_id),
          letter = (SELECT s.grade FROM lab_session s WHERE s.id = attempt.session_id),
          returned_at = (SELECT CASE WHEN s.status = 'returned' THEN s.returned_at END
                         FROM lab_session s WHERE s.id = attempt.session_id),
          released_at = (SELECT CASE WHEN s.status = 'graded' THEN s.graded_at END
                         FROM lab_session s WHERE s.id = attempt.session_id)
        WHERE attempt.number = (SELECT max(a.number) FROM attempt a
                                WHERE a.session_id = attempt.session_id)
        """
    )
    bind = op.get_bind()
    rows = bind.execute(sa.text('SELECT id, letter FROM attempt WHERE letter IS NOT NULL'))
    for attempt_id, letter in rows.fetchall():
        try:
            points = float(letter.replace(',', '.'))
        except ValueError:
            continue
        if points == points and abs(points) < 1e9:
            bind.execute(sa.text('UPDATE attempt SET points = :p, letter = NULL WHERE id = :i'),
                         {'p': points, 'i': attempt_id})
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        for name in ('grade', 'feedback', 'feedback_positions', 'graded_at', 'returned_at'):
            batch_op.drop_column(name)


def downgrade() -> None:
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        batch_op.add_column(sa.Column('grade', TEXT(length=32), nullable=True))
        batch_op.add_column(sa.Column('feedback', TEXT(length=20000), nullable=False,
                                      server_default=''))
        batch_op.add_column(sa.Column('feedback_positions', TEXT(length=20000),
                                      nullable=False, server_default='{}'))
        batch_op.add_column(sa.Column('graded_at', WHEN(), nullable=True))
        batch_op.add_column(sa.Column('returned_at', WHEN(), nullable=True))
    op.execute(
        """
        UPDATE lab_session SET
          feedback = coalesce((SELECT a.feedback FROM attempt a WHERE a.session_id = lab_session.id
                               ORDER BY a.number DESC LIMIT 1), ''),
          grade = (SELECT coalesce(a.letter, CAST(a.points AS VARCHAR)) FROM attempt a
                   WHERE a.session_id = lab_session.id ORDER BY a.number DESC LIMIT 1)
        """
    )
    op.drop_table('extension')
    with op.batch_alter_table('attempt', schema=None) as batch_op:
        for name in ('seen_at', 'released_at', 'returned_at', 'letter', 'rubric_points',
                     'points', 'feedback_positions', 'feedback'):
            batch_op.drop_column(name)
    with op.batch_alter_table('take', schema=None) as batch_op:
        batch_op.drop_column('trim_start')
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.drop_column('rubric')
        batch_op.drop_column('max_points')
    with op.batch_alter_table('course', schema=None) as batch_op:
        batch_op.drop_column('timezone')
