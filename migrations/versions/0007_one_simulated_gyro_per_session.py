"""one simulated gyro timeline per lab session; the virtual turntable's tilt, misalignment
and part B plane; assignment ranges for the table draws; the symmetric recording order; a
real gyro's uploaded Allan characterisation per assignment

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-22 17:00:00
"""
from collections.abc import Sequence

import sqlalchemy as sa
import sqlmodel
from alembic import op


revision: str = '0007'
down_revision: str | None = '0006'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

SESSION_FLOATS = ('sim_pitch_deg', 'sim_roll_deg', 'sim_misalign_h_deg', 'sim_misalign_v_deg',
                  'sim_plane_dial_deg')


def upgrade() -> None:
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.add_column(sa.Column('table_tilt_max_deg', sa.Float(), nullable=True))
        batch_op.add_column(sa.Column('misalignment_max_deg', sa.Float(), nullable=True))
        batch_op.add_column(sa.Column('gyro_characterisation',
                                      sqlmodel.sql.sqltypes.AutoString(length=4000),
                                      nullable=True))
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        for name in SESSION_FLOATS:
            batch_op.add_column(sa.Column(name, sa.Float(), nullable=True))
        batch_op.add_column(sa.Column('sim_clock_s', sa.Float(), nullable=False,
                                      server_default='0'))
        batch_op.add_column(sa.Column('sim_clock_at', sqlmodel.sql.sqltypes.UTCDateTime(),
                                      nullable=True))
        batch_op.add_column(sa.Column('symmetric_order', sa.Boolean(), nullable=False,
                                      server_default=sa.false()))


def downgrade() -> None:
    with op.batch_alter_table('lab_session', schema=None) as batch_op:
        batch_op.drop_column('symmetric_order')
        batch_op.drop_column('sim_clock_at')
        batch_op.drop_column('sim_clock_s')
        for name in reversed(SESSION_FLOATS):
            batch_op.drop_column(name)
    with op.batch_alter_table('assignment', schema=None) as batch_op:
        batch_op.drop_column('gyro_characterisation')
        batch_op.drop_column('misalignment_max_deg')
        batch_op.drop_column('table_tilt_max_deg')
