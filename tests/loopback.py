"""One TLS context for the tests' httpx clients of the servers they start on loopback.

httpx builds a TLS context for every client it makes, plain-http ones too, loading the CA
bundle each time (≈ 20 ms of CPU): a client per poll or per request cost the suite ≈ 40 s
of its CPU (py-spy over a whole run).  A context is safe to share between clients and
threads."""

from __future__ import annotations

import httpx

TLS = httpx.create_ssl_context()
