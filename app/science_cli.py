"""``gyrolab solve`` / ``simulate`` / ``allan`` (added with the science core)."""


def add_science_commands(commands) -> None:
    return None
