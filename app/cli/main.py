"""The ``gyrolab`` command: serve, migrate, create-user, and the science commands."""

from __future__ import annotations

import argparse
import getpass
import os
import sys

from app.cli.language import speaker
from app.cli.localised_parser import help_speaker, parser_class, wanted_language


def _serve(args: argparse.Namespace) -> int:
    import uvicorn

    from app.cli.demo import (
        create_demo_data,
        database_is_empty,
        format_credentials,
        write_credentials_file,
    )
    from app.config import get_settings
    from app.db import write_session
    from app.lab.stream import MAX_FRAME_BYTES
    from app.migrate import upgrade_to_head

    say = speaker(args)
    settings = get_settings()
    upgrade_to_head()
    credentials_file = settings.var_dir / "demo-credentials.txt"
    if not args.no_demo:
        with write_session() as db:
            credentials = create_demo_data(db) if database_is_empty(db) else None
        if credentials:
            write_credentials_file(credentials_file, credentials)
            print(format_credentials(credentials, say), flush=True)
            print(say("cli.demo_saved", path=credentials_file), flush=True)
        elif credentials_file.exists():
            print(say("cli.demo_see", path=credentials_file), flush=True)
    host = args.host or settings.host
    port = args.port or settings.port
    print(say("cli.serving", url=f"http://{host}:{port}"), flush=True)
    uvicorn.run(
        "app.main:app",
        host=host,
        port=port,
        workers=args.workers,
        proxy_headers=args.proxy_headers,
        access_log=not args.no_access_log,
        # Idle keep-alive connections stay open longer than a student's pause between
        # requests (uvicorn's 5 s default closed them while a client was sending its next
        # request on them: "connection reset" under load) and than a proxy's idle timeout.
        timeout_keep_alive=KEEP_ALIVE_S,
        # The stream's frames (a few hundred bytes of JSON, five a second) are sent as they
        # are: compressing each one cost more of the worker's one core than anything else
        # in a frame (py-spy under the 60-student load test), to save bytes no network here
        # is short of.
        ws_per_message_deflate=False,
        ws_max_size=MAX_FRAME_BYTES,
    )
    return 0


KEEP_ALIVE_S = 75


def _migrate(_args: argparse.Namespace) -> int:
    from app.migrate import upgrade_to_head

    upgrade_to_head()
    print(speaker()("cli.migrated"))
    return 0


def _create_user(args: argparse.Namespace) -> int:
    from app.accounts.security import MIN_PASSWORD_LENGTH, password_problem
    from app.accounts.service import create_user
    from app.core.exceptions import UserError
    from app.db import write_session
    from app.migrate import upgrade_to_head
    from app.models import Role

    say = speaker(args)
    password = args.password
    if password is None:
        if not sys.stdin.isatty():
            password = sys.stdin.readline().rstrip("\n")
        else:
            password = getpass.getpass(say("cli.password_prompt"))
            if getpass.getpass(say("cli.password_again")) != password:
                print(say("cli.error", message=say("cli.passwords_differ")), file=sys.stderr)
                return 2
    problem = password_problem(password, args.username)
    if problem:
        reason = say(problem, minimum=MIN_PASSWORD_LENGTH)
        message = say("cli.password_unacceptable", problem=reason)
        print(say("cli.error", message=message), file=sys.stderr)
        return 2
    upgrade_to_head()
    try:
        with write_session() as db:
            create_user(
                db,
                username=args.username,
                display_name=args.display_name or args.username,
                role=Role(args.role),
                password=password,
                email=args.email,
            )
    except UserError as error:
        print(say("cli.error", message=say(error.key, **error.params)), file=sys.stderr)
        return 2
    print(say("cli.user_created", role=say(f"role.{args.role}"), username=args.username))
    return 0


def _prune(args: argparse.Namespace) -> int:
    from app.db import write_session
    from app.lab.prune import prune_takes
    from app.migrate import upgrade_to_head

    upgrade_to_head()
    with write_session() as db:
        pruned = prune_takes(db, args.days)
    megabytes = f"{pruned.bytes / 1e6:.1f}"
    print(speaker()("cli.pruned", takes=pruned.takes, days=args.days, megabytes=megabytes))
    return 0


def _backup(args: argparse.Namespace) -> int:
    from pathlib import Path

    from app.cli.backup import BackupError, backup, postgres_hint, sqlite_path
    from app.config import get_settings

    say = speaker(args)
    url = get_settings().database_url
    try:
        database = sqlite_path(url)
        if database is None:
            print(postgres_hint(url, "backup", args.file))
            return 2
        backup(database, Path(args.file))
    except BackupError as error:
        print(f"gyrolab backup: {say(error.key, **error.params)}", file=sys.stderr)
        return 2
    print(say("cli.backed_up", database=database, file=args.file))
    return 0


def _restore(args: argparse.Namespace) -> int:
    from pathlib import Path

    from app.cli.backup import BackupError, postgres_hint, restore, sqlite_path
    from app.config import get_settings
    from app.migrate import upgrade_to_head
    from app.serving_lock import servers_using

    say = speaker(args)
    url = get_settings().database_url
    try:
        database = sqlite_path(url)
        if database is None:
            print(postgres_hint(url, "restore", args.file))
            return 2
        if not args.yes:
            print(f"gyrolab restore: {say('cli.restore_needs_yes')}", file=sys.stderr)
            return 2
        if servers_using(url):
            print(f"gyrolab restore: {say('cli.restore_server_running')}", file=sys.stderr)
            return 2
        restore(Path(args.file), database)
    except BackupError as error:
        print(f"gyrolab restore: {say(error.key, **error.params)}", file=sys.stderr)
        return 2
    upgrade_to_head()
    print(say("cli.restored", database=database, file=args.file))
    return 0


def build_parser(language: str = "en") -> argparse.ArgumentParser:
    """Every command's parser, its help and argparse's own words in ``language``."""
    say = help_speaker(language)
    parser = parser_class(language)(prog="gyrolab", description=say("clihelp.about"))
    commands = parser.add_subparsers(dest="command", required=True)

    serve = commands.add_parser("serve", help=say("clihelp.serve"))
    serve.add_argument("--host", help=say("clihelp.serve.host"))
    serve.add_argument("--port", type=int, help=say("clihelp.serve.port"))
    serve.add_argument("--workers", type=int, default=1)
    serve.add_argument("--no-demo", action="store_true", help=say("clihelp.serve.no_demo"))
    serve.add_argument(
        "--proxy-headers", action="store_true", help=say("clihelp.serve.proxy_headers")
    )
    serve.add_argument("--no-access-log", action="store_true")
    serve.set_defaults(handler=_serve)

    migrate = commands.add_parser("migrate", help=say("clihelp.migrate"))
    migrate.set_defaults(handler=_migrate)

    create = commands.add_parser("create-user", help=say("clihelp.create_user"))
    create.add_argument("--role", choices=["admin", "teacher", "student"], default="teacher")
    create.add_argument("--username", required=True)
    create.add_argument("--display-name")
    create.add_argument("--email")
    create.add_argument("--password", help=say("clihelp.create_user.password"))
    create.set_defaults(handler=_create_user)

    prune = commands.add_parser("prune", help=say("clihelp.prune"))
    prune.add_argument("--days", type=int, default=30, help=say("clihelp.prune.days"))
    prune.set_defaults(handler=_prune)
    backup = commands.add_parser("backup", help=say("clihelp.backup"))
    backup.add_argument("file", help=say("clihelp.backup.file"))
    backup.set_defaults(handler=_backup)
    restore = commands.add_parser("restore", help=say("clihelp.restore"))
    restore.add_argument("file")
    restore.add_argument("--yes", action="store_true", help=say("clihelp.restore.yes"))
    restore.set_defaults(handler=_restore)

    from app.cli.bridge import add_bridge_command

    add_bridge_command(commands, say)

    from app.cli.lti import add_lti_commands
    from app.cli.science import add_science_commands

    add_science_commands(commands, say)
    add_lti_commands(commands, say)
    return parser


def main(argv: list[str] | None = None) -> int:
    arguments = sys.argv[1:] if argv is None else argv
    args = build_parser(wanted_language(arguments)).parse_args(arguments)
    try:
        return args.handler(args)
    except BrokenPipeError:
        # the reader went away (``gyrolab simulate … | head``): what it read is all it wanted;
        # stdout pointed at nothing, so that closing it at exit cannot raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:
        # (imported only now: the science commands never load the database's modules)
        from app.db import database_busy

        if not database_busy(error):
            raise
        # another writer held the write lock past the busy timeout (SQLite's, PostgreSQL's
        # lock_timeout): nothing was written; a sentence, not a traceback
        say = speaker(args)
        print(say("cli.error", message=say("error.busy")), file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
