"""GyroLab inside a university's LMS: an LTI 1.3 tool with LTI Advantage.

pylti1p3 (the maintained ``pylti1p3next``) does the protocol -- the OIDC login
initiation, the id_token's signature and claims, deep-linking responses, the service
calls; this package adapts it to Starlette and the database (``handshake``), keeps the
platforms and GyroLab's keys (``platforms``, ``keys``), turns a launch into accounts,
courses and sessions (``provisioning``), and talks to the LMS's services: rosters
(``roster``, NRPS) and grades (``grades``, AGS).
"""
