"""Local time: due dates are typed and shown in the course's IANA time zone and stored in UTC."""

from __future__ import annotations

from datetime import UTC, datetime
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from app.config import iana_zones
from app.core.exceptions import UserError

COMMON_ZONES = (
    "Asia/Shanghai",
    "Asia/Hong_Kong",
    "Asia/Taipei",
    "Asia/Tokyo",
    "Asia/Singapore",
    "Europe/London",
    "Europe/Berlin",
    "America/New_York",
    "America/Los_Angeles",
    "Australia/Sydney",
    "UTC",
)


def server_zone_name() -> str:
    """The server's default zone (``GYROLAB_TIMEZONE``, default Asia/Shanghai)."""
    from app.config import get_settings

    return get_settings().timezone


def zone(name: str | None) -> ZoneInfo:
    """A course's zone by name; the server's when ``name`` is None or unknown."""
    for candidate in (name, server_zone_name(), "UTC"):
        if candidate:
            try:
                return ZoneInfo(candidate)
            except (ZoneInfoNotFoundError, ValueError):
                continue
    return ZoneInfo("UTC")


def valid_zone_name(name: str) -> str:
    """``name`` if it is an IANA zone, else a UserError."""
    name = name.strip()
    if name not in iana_zones():
        raise UserError("course.bad_timezone", name=name[:64])
    return name


def zone_choices() -> list[str]:
    """The zones offered in a course's settings: common ones first, then all others."""
    rest = sorted(iana_zones() - set(COMMON_ZONES))
    return [*COMMON_ZONES, *rest]


def local_input_to_utc(value: datetime, zone_name: str | None) -> datetime:
    """A wall-clock time typed in the course's zone (naive) as an aware UTC datetime."""
    if value.tzinfo is not None:
        return value.astimezone(UTC)
    return value.replace(tzinfo=zone(zone_name)).astimezone(UTC)


def utc_to_local_input(value: datetime | None, zone_name: str | None) -> str:
    """A stored UTC datetime as the ``datetime-local`` input's value in the course's zone."""
    if value is None:
        return ""
    aware = value if value.tzinfo else value.replace(tzinfo=UTC)
    return aware.astimezone(zone(zone_name)).strftime("%Y-%m-%dT%H:%M")
