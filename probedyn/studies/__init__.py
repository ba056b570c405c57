"""Studies that compose the pipeline end to end: probes reduced from their FEM (``probes/``,
``lumped/``) driving the manipulation schemes (``schemes/``).  Library code (plain data in SI
units, no printing, plotting or prose): the CLI and the report present the results."""
