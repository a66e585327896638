"""``gyrolab lti …``: register LMSs, rotate GyroLab's LTI key, send grades, sync rosters."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from sqlmodel import select

from app.cli.language import speaker
from app.core.exceptions import UserError


def _on_a_current_database(handler: Callable[[argparse.Namespace], int]):
    """``handler`` run after the database is brought to the newest schema, as
    ``create-user`` runs: an administrator registers the LMS before the server's first
    start, or after an upgrade, and met SQLAlchemy's "no such table" traceback."""

    def run(args: argparse.Namespace) -> int:
        from app.migrate import upgrade_to_head

        upgrade_to_head()
        return handler(args)

    return run


def _add_platform(args: argparse.Namespace) -> int:
    from app.db import write_session
    from app.lti.platforms import PlatformFields, add_platform

    say = speaker()

    fields = PlatformFields(
        name=args.name or "",
        issuer=args.issuer,
        client_id=args.client_id,
        auth_login_url=args.login_url,
        auth_token_url=args.token_url,
        key_set_url=args.jwks_url,
        deployment_ids=args.deployment or [],
        auth_audience=args.audience,
    )
    try:
        with write_session() as db:
            platform = add_platform(db, fields)
            issuer, client = platform.issuer, platform.client_id
            print(say("cli.lti_registered", name=platform.name, issuer=issuer, client=client))
    except UserError as error:
        print(f"gyrolab lti add-platform: {say(error.key, **error.params)}", file=sys.stderr)
        return 2
    return 0


def _list(_args: argparse.Namespace) -> int:
    from app.db import read_session
    from app.lti.platforms import deployments_of
    from app.models import LtiPlatform

    with read_session() as db:
        platforms = db.exec(select(LtiPlatform).order_by(LtiPlatform.id)).all()
        for platform in platforms:
            deployments = ",".join(deployments_of(platform)) or "-"
            print(
                f"{platform.id}\t{platform.name}\t{platform.issuer}\t{platform.client_id}"
                f"\t{deployments}\t{platform.registered_by}"
            )
    if not platforms:  # said on stderr: the rows on stdout stay a script's to count
        print(speaker()("cli.lti_no_platforms"), file=sys.stderr)
    return 0


def _rotate(_args: argparse.Namespace) -> int:
    from app.db import write_session
    from app.lti import keys

    with write_session() as db:
        key = keys.rotate(db)
        days = keys.KEEP_RETIRED.days
        print(speaker()("cli.lti_new_key", kid=key.kid, days=days))
    return 0


def _registration_link(args: argparse.Namespace) -> int:
    from app.config import get_settings
    from app.db import write_session
    from app.lti.registration import new_registration_link

    base = (args.base_url or get_settings().public_url or "").rstrip("/")
    if not base:
        message = speaker()("cli.lti_needs_base_url")
        print(f"gyrolab lti registration-link: {message}", file=sys.stderr)
        return 2
    with write_session() as db:
        token = new_registration_link(db)
    print(f"{base}/lti/register?token={token}")
    return 0


def _send_grades(_args: argparse.Namespace) -> int:
    from app.lti.grades import send_due

    counts = send_due()
    print(speaker()("cli.lti_grades_sent", sent=counts["sent"], failed=counts["failed"]))
    return 1 if counts["failed"] else 0


def _sync_roster(args: argparse.Namespace) -> int:
    from app.db import read_session
    from app.lti.roster import sync_roster
    from app.models import LtiContext

    say = speaker()
    with read_session() as db:
        contexts = db.exec(select(LtiContext.id).where(LtiContext.course_id == args.course)).all()
    if not contexts:
        message = say("cli.lti_not_linked", course=args.course)
        print(f"gyrolab lti sync-roster: {message}", file=sys.stderr)
        return 2
    failed = False
    for context_id in contexts:
        outcome = sync_roster(context_id)
        failed |= outcome.problem is not None
        synced = say("cli.lti_roster_synced", students=outcome.students, new=outcome.newly_enrolled)
        print(outcome.problem or synced)
    return 1 if failed else 0


def add_lti_commands(commands, say) -> None:
    lti = commands.add_parser("lti", help=say("clihelp.lti"))
    sub = lti.add_subparsers(dest="lti_command", required=True)
    add = sub.add_parser("add-platform", help=say("clihelp.lti.add_platform"))
    add.add_argument("--name")
    add.add_argument("--issuer", required=True)
    add.add_argument("--client-id", required=True)
    add.add_argument("--login-url", required=True, help=say("clihelp.lti.add_platform.login_url"))
    add.add_argument("--token-url", required=True, help=say("clihelp.lti.add_platform.token_url"))
    add.add_argument("--jwks-url", required=True, help=say("clihelp.lti.add_platform.jwks_url"))
    add.add_argument("--audience", help=say("clihelp.lti.add_platform.audience"))
    add.add_argument(
        "--deployment", action="append", help=say("clihelp.lti.add_platform.deployment")
    )
    add.set_defaults(handler=_on_a_current_database(_add_platform))
    sub.add_parser("list", help=say("clihelp.lti.list")).set_defaults(
        handler=_on_a_current_database(_list)
    )
    sub.add_parser("rotate-key", help=say("clihelp.lti.rotate_key")).set_defaults(
        handler=_on_a_current_database(_rotate)
    )
    link = sub.add_parser("registration-link", help=say("clihelp.lti.registration_link"))
    link.add_argument("--base-url", help=say("clihelp.lti.registration_link.base_url"))
    link.set_defaults(handler=_on_a_current_database(_registration_link))
    sub.add_parser("send-grades", help=say("clihelp.lti.send_grades")).set_defaults(
        handler=_on_a_current_database(_send_grades)
    )
    sync = sub.add_parser("sync-roster", help=say("clihelp.lti.sync_roster"))
    sync.add_argument(
        "--course", type=int, required=True, help=say("clihelp.lti.sync_roster.course")
    )
    sync.set_defaults(handler=_on_a_current_database(_sync_roster))
