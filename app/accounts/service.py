"""Account and roster operations shared by pages, the CLI and demo data."""

from __future__ import annotations

from dataclasses import dataclass

from sqlmodel import Session, select

from app.accounts.roster_csv import RosterProblem, RosterRow
from app.accounts.security import (
    generate_password,
    hash_password,
    normalise_username,
    revoke_credentials,
)
from app.core.exceptions import UserError
from app.core.text_files import plain_text, shown_name
from app.models import Course, Enrollment, Role, User, new_join_code


@dataclass
class NewCredential:
    username: str
    display_name: str
    password: str


def find_user(db: Session, username: str) -> User | None:
    return db.exec(select(User).where(User.username == normalise_username(username))).first()


def create_user(
    db: Session,
    *,
    username: str,
    display_name: str,
    role: Role,
    password: str,
    email: str | None = None,
    must_change_password: bool = False,
    created_by: User | None = None,
) -> User:
    if find_user(db, username) is not None:
        raise UserError("account.exists", username=username)
    user = User(
        username=normalise_username(username),
        display_name=shown_name(display_name),
        email=email,
        role=role.value,
        password_hash=hash_password(password),
        must_change_password=must_change_password,
        created_by_id=created_by.id if created_by is not None else None,
    )
    db.add(user)
    db.flush()
    return user


def enroll(db: Session, course: Course, student: User) -> bool:
    """Add a student to a course; False when already enrolled."""
    existing = db.exec(
        select(Enrollment).where(
            Enrollment.course_id == course.id, Enrollment.student_id == student.id
        )
    ).first()
    if existing is not None:
        return False
    db.add(Enrollment(course_id=course.id, student_id=student.id))
    db.flush()
    return True


def add_student(
    db: Session,
    course: Course,
    username: str,
    display_name: str,
    email: str | None,
) -> NewCredential | None:
    """Create a student with a one-time password (returned) and enroll them, or enroll an
    account this course's teacher created earlier (None).

    Any other existing account needs the student's consent: they join with the course's
    code, so a teacher can never take over a student who belongs to someone else.
    """
    user = find_user(db, username)
    if user is not None:
        if user.role != Role.student:
            raise UserError("account.not_student", username=username)
        if user.created_by_id != course.teacher_id:
            raise UserError("roster.needs_consent", username=user.username, code=course.join_code)
        enroll(db, course, user)
        return None
    password = generate_password()
    user = create_user(
        db,
        username=username,
        display_name=display_name,
        role=Role.student,
        password=password,
        email=email,
        must_change_password=True,
        created_by=db.get(User, course.teacher_id),
    )
    enroll(db, course, user)
    return NewCredential(user.username, user.display_name, password)


def check_roster_against_accounts(db: Session, rows: list[RosterRow]) -> list[RosterProblem]:
    """Rows whose username already belongs to a teacher cannot be imported."""
    problems = []
    for row in rows:
        user = find_user(db, row.username)
        if user is not None and user.role != Role.student:
            problems.append(RosterProblem(row.line, "roster.not_student", {"value": row.username}))
    return problems


@dataclass
class RosterImport:
    created: list[NewCredential]
    enrolled: list[str]  # accounts this teacher had created before
    needs_code: list[str]  # other existing accounts: they join with the course code


def import_roster(db: Session, course: Course, rows: list[RosterRow]) -> RosterImport:
    """Create/enroll every row (caller commits once)."""
    outcome = RosterImport([], [], [])
    for row in rows:
        try:
            credential = add_student(db, course, row.username, row.display_name, row.email)
        except UserError as error:
            if error.key != "roster.needs_consent":
                raise
            outcome.needs_code.append(normalise_username(row.username))
            continue
        if credential is None:
            outcome.enrolled.append(normalise_username(row.username))
        else:
            outcome.created.append(credential)
    return outcome


def join_course(db: Session, student: User, code: str) -> Course:
    """The student's own consent: enroll with a course's join code (case and spaces ignored)."""
    if student.role != Role.student:
        raise UserError("join.students_only")
    wanted = typed_join_code(code)
    course = db.exec(select(Course).where(Course.join_code == wanted)).first() if wanted else None
    if course is None or course.archived:
        raise UserError("join.bad_code")
    enroll(db, course, student)
    return course


def typed_join_code(code: str) -> str:
    """A join code as a student types it, as stored: without spaces or dashes, upper case,
    full-width letters and digits (a Chinese input method's) as plain ones."""
    return "".join(plain_text(code).replace("-", " ").split()).upper()[:16]


def course_by_code(db: Session, code: str) -> Course | None:
    wanted = typed_join_code(code)
    if not wanted:
        return None
    course = db.exec(select(Course).where(Course.join_code == wanted)).first()
    return None if course is None or course.archived else course


def rotate_join_code(db: Session, course: Course) -> None:
    """A new code; the old one (and links with it) stop working."""
    course.join_code = new_join_code()
    db.add(course)


def teaches_student(db: Session, teacher: User, student: User) -> bool:
    """Whether one of the teacher's courses holds the student."""
    found = db.exec(
        select(Enrollment.id)
        .join(Course, Course.id == Enrollment.course_id)
        .where(Enrollment.student_id == student.id, Course.teacher_id == teacher.id)
    ).first()
    return found is not None


def held_by_another_teacher(db: Session, student: User, teacher: User) -> bool:
    """Whether a course of a teacher other than ``teacher`` holds this student."""
    other = db.exec(
        select(Enrollment.id)
        .join(Course, Course.id == Enrollment.course_id)
        .where(Enrollment.student_id == student.id, Course.teacher_id != teacher.id)
    ).first()
    return other is not None


def may_reset_password(db: Session, actor: User, user: User) -> bool:
    """Who may give an account a new one-time password.

    An administrator: any account but another administrator's (and not their own: they use
    the password page).  A teacher: only a student account their own roster created, and
    only while no other teacher's course holds it -- otherwise an administrator does it.
    """
    if actor.id == user.id:
        return False
    if actor.role == Role.admin:
        return user.role != Role.admin
    if actor.role == Role.teacher:
        return (
            user.role == Role.student
            and user.created_by_id == actor.id
            and not held_by_another_teacher(db, user, actor)
        )
    return False


def reset_password(db: Session, user: User) -> str:
    """New one-time password; the user must change it, and every login session and API
    token of theirs ends."""
    password = generate_password()
    user.password_hash = hash_password(password)
    user.must_change_password = True
    db.add(user)
    revoke_credentials(db, user.id)
    return password
