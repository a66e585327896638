"""GyroLab's science core: pure numpy (plus scipy/allantools), no web imports.

Modules: ``units`` (rate units), ``exceptions`` (input errors students understand),
``solve`` (N-position least squares, heading, latitude, uncertainties, two-position),
``readings`` (CSV formats), ``explain`` (the handout's worked calculation),
``simulate`` (FOG + turntable simulator and presets), ``allan`` (Allan deviation),
``error_analysis`` (first-order heading errors and Monte Carlo).
Conventions: lab-reference.md §3.  Rates in °/h, angles in degrees.
"""
