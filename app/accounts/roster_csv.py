"""Parse a class roster: username (or student number), display name, optional email.

Accepts a CSV in UTF-8 (with or without BOM) or GB18030 (what Excel in a Chinese locale
writes), comma, semicolon or tab separated, or an Excel workbook (.xlsx, its first sheet:
:mod:`app.accounts.roster_workbook`), with or without a header row (and up to three title
lines above it, as a student system's export has).  Returns every row's
problems at once so a teacher can fix the file in one go; callers create nothing when any
row has a problem.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field

from app.accounts.roster_workbook import is_workbook, workbook_rows
from app.core.exceptions import UserError
from app.core.text_files import decode_text, plain_text, shown_name

MAX_ROSTER_BYTES = 1_000_000
MAX_ROSTER_ROWS = 2000
USERNAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}$")
# a student number as a spreadsheet saved a numeric column: "2023010102.0", "2.0230101E+09"
SPREADSHEET_NUMBER = re.compile(r"\d+\.0+|\d(?:\.\d+)?[eE][+]?\d+")
EMAIL_RE = re.compile(r"^[^@\s]+@[^@\s]+\.[^@\s]+$")
MAX_NAME = 128
TITLE_LINES = 3  # lines of one cell above the header row (a title, a term, a date)


def person_problems(username: str, display_name: str, email: str = "") -> dict[str, UserError]:
    """Every problem with one person typed into a form, at once: field name → UserError
    (in the form's order; empty when all is well).  The values arrive stripped."""
    problems: dict[str, UserError] = {}
    if not USERNAME_RE.match(plain_text(username)):  # as normalise_username stores it
        problems["username"] = UserError("roster.bad_username", value=username)
    if not shown_name(display_name):
        problems["display_name"] = UserError("roster.name_required")
    elif len(display_name) > MAX_NAME:
        problems["display_name"] = UserError("roster.name_too_long", value=username)
    if email and not EMAIL_RE.match(email):
        problems["email"] = UserError("roster.bad_email", value=email)
    return problems


HEADER_NAMES = {
    "username": {
        "username",
        "user",
        "login",
        "student_number",
        "student number",
        "student_id",
        "student id",
        "学号",
        "学生学号",
        "用户名",
        "用户名/学号",  # the one-time passwords' download names its columns as the page does
        "username / student number",
        "账号",
        "student no.",
        "student no",
        "student #",
        "id number",
        "学工号",
        "学生编号",
        "学籍号",
    },
    "display_name": {
        "display_name",
        "display name",
        "name",
        "full name",
        "姓名",
        "学生姓名",
        "名字",
    },
    "email": {
        "email",
        "e-mail",
        "mail",
        "email address",
        "e-mail address",
        "邮箱",
        "电子邮件",
        "电子邮箱",
    },
}


@dataclass(frozen=True)
class RosterRow:
    line: int
    username: str
    display_name: str
    email: str | None


@dataclass
class RosterProblem:
    line: int
    key: str  # message key (locales/*/LC_MESSAGES/messages.po)
    params: dict = field(default_factory=dict)


@dataclass
class RosterParse:
    rows: list[RosterRow]
    problems: list[RosterProblem]

    @property
    def ok(self) -> bool:
        return not self.problems and bool(self.rows)


def _header_map(cells: list[str]) -> dict[str, int] | None:
    """The columns a header row names (by :data:`HEADER_NAMES`, full-width forms and the
    spaces of "姓 名" aside), or None when it names no username column."""
    mapping: dict[str, int] = {}
    for index, cell in enumerate(cells):
        name = " ".join(plain_text(cell).lower().split())
        for column, aliases in HEADER_NAMES.items():
            if (name in aliases or name.replace(" ", "") in aliases) and column not in mapping:
                mapping[column] = index
    return mapping if "username" in mapping else None


def _header_index(lines: list[tuple[int, list[str]]]) -> int | None:
    """Which of the first lines is the header: the first that names a username column,
    with at most ``TITLE_LINES`` lines of one cell each above it (a student system's
    export: "2026 秋 惯性导航 名单", a date); None for a roster without one."""
    for index, (_number, cells) in enumerate(lines[: TITLE_LINES + 1]):
        if _header_map(cells) is not None:
            return index
        if sum(bool(cell.strip()) for cell in cells) != 1:  # a row of a headerless roster
            return None
    return None


def _dialect(text: str) -> type[csv.Dialect] | csv.Dialect:
    """The roster's separator, sniffed from its lines from the first that holds one: a
    student system's title lines above the header hold none ("课程名称：惯性导航"), and
    sniffing them with the table took a tab-separated export for one column."""
    lines = text.splitlines()
    first = next((k for k, line in enumerate(lines) if any(c in line for c in ",;\t")), 0)
    try:
        return csv.Sniffer().sniff("\n".join(lines[first : first + 50])[:4096], delimiters=",;\t")
    except csv.Error:
        return csv.excel


def parse_roster(data: bytes) -> RosterParse:
    if len(data) > MAX_ROSTER_BYTES:
        return RosterParse(
            [], [RosterProblem(0, "roster.too_large", {"limit_kb": MAX_ROSTER_BYTES // 1000})]
        )
    if is_workbook(data):
        try:  # the header row and one more than the most students: "too many" then
            lines = workbook_rows(data, MAX_ROSTER_ROWS + 1)
        except UserError as error:
            return RosterParse([], [RosterProblem(0, error.key, error.params)])
    else:
        try:
            text = decode_text(data)
        except UserError:
            return RosterParse([], [RosterProblem(0, "roster.encoding")])
        dialect = _dialect(text)
        lines = [
            (number, cells)
            for number, cells in enumerate(csv.reader(io.StringIO(text), dialect), start=1)
            if any(cell.strip() for cell in cells)
        ]
    if not lines:
        return RosterParse([], [RosterProblem(0, "roster.empty_file")])
    header_at = _header_index(lines)
    if header_at is None:
        mapping = {"username": 0, "display_name": 1, "email": 2}
    else:
        header_line, header = lines[header_at]
        mapping = _header_map(header) or {}
        lines = lines[header_at + 1 :]
        if "display_name" not in mapping:
            return RosterParse([], [RosterProblem(header_line, "roster.no_name_column")])
    if len(lines) > MAX_ROSTER_ROWS:
        return RosterParse([], [RosterProblem(0, "roster.too_many", {"limit": MAX_ROSTER_ROWS})])

    rows: list[RosterRow] = []
    problems: list[RosterProblem] = []
    seen: dict[str, int] = {}
    for number, cells in lines:

        def cell(column: str, cells=cells) -> str:
            index = mapping.get(column)
            return cells[index].strip() if index is not None and index < len(cells) else ""

        # a student number typed in full-width forms ("２０２３…") is the same number
        username = plain_text(cell("username"))
        name, email = shown_name(cell("display_name")), cell("email")
        if SPREADSHEET_NUMBER.fullmatch(username):
            problems.append(
                RosterProblem(number, "roster.number_from_spreadsheet", {"value": username})
            )
            continue
        if not USERNAME_RE.match(username):
            problems.append(RosterProblem(number, "roster.bad_username", {"value": username}))
            continue
        if not name:
            problems.append(RosterProblem(number, "roster.no_name", {"value": username}))
            continue
        if len(name) > MAX_NAME:
            problems.append(RosterProblem(number, "roster.name_too_long", {"value": username}))
            continue
        if email and not EMAIL_RE.match(email):
            problems.append(RosterProblem(number, "roster.bad_email", {"value": email}))
            continue
        key = username.lower()
        if key in seen:
            problems.append(
                RosterProblem(number, "roster.duplicate", {"value": username, "other": seen[key]})
            )
            continue
        seen[key] = number
        rows.append(RosterRow(number, username, name, email or None))
    return RosterParse(rows, problems)
