"""Lab reports: a session's or a submitted attempt's work as a bilingual PDF."""
