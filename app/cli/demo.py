"""Demo data for a newcomer: one teacher, three students, one course."""

from __future__ import annotations

import os
import random
from pathlib import Path

from sqlmodel import Session, func, select

from app.accounts.security import generate_password
from app.accounts.service import create_user, enroll
from app.core.solve import solve_heading
from app.lab.service import record_position
from app.lab.sessions import SessionSettings, start_session
from app.lab.sim import SimulatedTake, north_dial_deg, set_gyro_clock
from app.lab.submissions import submit
from app.lab.truth import draw_truth
from app.models import Assignment, Course, InputMethod, LabSession, Role, User

DEMO_TEACHER = ("teacher", "Demo Teacher 王老师")
DEMO_STUDENTS = (
    ("student1", "张三 Zhang San"),
    ("student2", "李四 Li Si"),
    ("student3", "王五 Wang Wu"),
)
DEMO_COURSE = "Demo: FOG north-finding lab 光纤陀螺寻北实验"
DEMO_ASSIGNMENT = "Four-position north finding 四位置法寻北"
DEMO_INSTRUCTIONS = (
    "Part A: turn the table counter-clockwise in 90° steps and take at least 10 readings at "
    "each position. Part B: turn the gyro in the north–south vertical plane.\n"
    "A 部分：转台逆时针每次转 90°，每个位置至少读 10 个数。B 部分：在南北竖直面内转动陀螺。"
)


def database_is_empty(db: Session) -> bool:
    return db.exec(select(func.count()).select_from(User)).one() == 0


def create_demo_data(db: Session) -> list[tuple[str, str, str]]:
    """Create the demo accounts, course, assignment and some students' work.

    Returns (role, username, password) rows.
    """
    credentials = []
    teacher_password = generate_password()
    teacher = create_user(
        db,
        username=DEMO_TEACHER[0],
        display_name=DEMO_TEACHER[1],
        role=Role.teacher,
        password=teacher_password,
    )
    credentials.append(("teacher", teacher.username, teacher_password))
    course = Course(name=DEMO_COURSE, teacher_id=teacher.id)
    db.add(course)
    db.flush()
    students = []
    for username, name in DEMO_STUDENTS:
        password = generate_password()
        student = create_user(
            db,
            username=username,
            display_name=name,
            role=Role.student,
            password=password,
            created_by=teacher,
        )
        enroll(db, course, student)
        students.append(student)
        credentials.append(("student", username, password))
    assignment = Assignment(
        course_id=course.id,
        title=DEMO_ASSIGNMENT,
        latitude_deg=39.93,
        earth_rate_deg_h=15.04,
        instructions=DEMO_INSTRUCTIONS,
        allowed_methods="manual,csv,simulator",
        simulator_preset="teaching-fog",
        min_readings=10,
    )
    db.add(assignment)
    db.flush()
    add_demo_work(db, assignment, students)
    return credentials


def add_demo_work(db: Session, assignment: Assignment, students: list[User]) -> None:
    """Two students submitted a full simulated run and the third has done part A only, so a
    newcomer's teacher dashboard shows real data."""
    rng = random.Random(2026)
    plans = [
        (students[0], ("heading", "latitude"), 300, True),
        (students[1], ("heading", "latitude"), 150, True),
        (students[2], ("heading",), 100, False),
    ]
    for student, parts, dwell, submit_it in plans:
        session, _ = start_session(db, student, SessionSettings(), assignment, assignment.title)
        # a demo the same on every machine: its own seeded gyro and truth
        session.sim_seed = rng.getrandbits(62)
        draw_truth(assignment, session, rng)
        db.flush()
        clock = 1200.0  # the student lets the gyro warm up for 20 min, then turns in 20 s
        recorded: dict[str, list] = {}
        for part in parts:
            if part == "latitude":  # the table is turned to the north part A found
                session.sim_plane_dial_deg = round(north_dial(session, recorded["heading"]), 1)
                session.sim_turns += 1
            for position in range(1, 5):
                if position > 1:
                    session.sim_turns += 1
                setattr(session, f"sim_table_{part}", position)
                take = SimulatedTake(session, part, position, settle_s=5.0, start_s=clock)
                values, times = take.next(int(dwell * take.rate_hz))
                clock = take.end_s + 20.0
                recorded.setdefault(part, []).append((take.dial_angle_deg, values))
                record_position(
                    db,
                    session,
                    part=part,
                    position=position,
                    values=values,
                    source=InputMethod.simulator,
                    times=times,
                    angle_deg=take.dial_angle_deg,
                )
        set_gyro_clock(session, clock)
        if submit_it:
            submit(db, session)


def north_dial(session: LabSession, recorded: list[tuple[float, object]]) -> float:
    """The horizontal dial (° clockwise from position 1) that points the axis north by the
    student's own part-A result, as the handout's step 4 does."""
    angles = [angle for angle, _ in recorded]
    result = solve_heading([values for _, values in recorded], angles)
    return north_dial_deg(session, result.azimuth_deg, angles[0])


def write_credentials_file(path: Path, credentials: list[tuple[str, str, str]]) -> None:
    lines = ["# GyroLab demo accounts (role, username, password)"]
    lines += [",".join(row) for row in credentials]
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as handle:
        handle.write("\n".join(lines) + "\n")


def format_credentials(credentials: list[tuple[str, str, str]], say) -> str:
    """The demo accounts as the command prints them, in its language (``say``)."""
    rows = [f"  {role:<8} {username:<10} {password}" for role, username, password in credentials]
    return "\n".join([say("cli.demo_accounts"), *rows])
