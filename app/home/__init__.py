"""The home page: each role's dashboard, above the lab and review it summarises."""
