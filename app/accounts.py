"""Account and roster operations shared by pages, the CLI and demo data."""

from __future__ import annotations

from dataclasses import dataclass

from sqlmodel import Session, select

from app.models import Course, Enrollment, Role, User
from app.roster import RosterProblem, RosterRow
from app.security import generate_password, hash_password, normalise_username, revoke_sessions


class AccountError(ValueError):
    """A message key explaining why an account operation was refused."""

    def __init__(self, key: str, **params: object) -> None:
        super().__init__(key)
        self.key = key
        self.params = params


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
) -> User:
    if find_user(db, username) is not None:
        raise AccountError("account.exists", username=username)
    user = User(
        username=normalise_username(username),
        display_name=display_name.strip(),
        email=email,
        role=role.value,
        password_hash=hash_password(password),
        must_change_password=must_change_password,
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
    db: Session, course: Course, username: str, display_name: str, email: str | None
) -> NewCredential | None:
    """Enroll an existing student, or create one with a one-time password (returned)."""
    user = find_user(db, username)
    if user is not None:
        if user.role != Role.student:
            raise AccountError("account.not_student", username=username)
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


def import_roster(
    db: Session, course: Course, rows: list[RosterRow]
) -> tuple[list[NewCredential], list[str]]:
    """Create/enroll every row (caller commits once): new credentials and enrolled usernames."""
    created: list[NewCredential] = []
    enrolled: list[str] = []
    for row in rows:
        credential = add_student(db, course, row.username, row.display_name, row.email)
        if credential is None:
            enrolled.append(normalise_username(row.username))
        else:
            created.append(credential)
    return created, enrolled


def reset_password(db: Session, user: User) -> str:
    """New one-time password; the user must change it and every session is revoked."""
    password = generate_password()
    user.password_hash = hash_password(password)
    user.must_change_password = True
    db.add(user)
    revoke_sessions(db, user.id)
    return password
