"""The Typer applications that command modules attach to."""

import typer

app = typer.Typer(
    name="probedyn",
    help="Dynamics of AFM probes as nanomanipulators: geometry -> FEM modes -> lumped model -> scheme.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
simulate_app = typer.Typer(help="Run a scheme (FFM line scan, nano-pushing, ...).", no_args_is_help=True)
sweep_app = typer.Typer(help="Parameter sweeps on Dask, results as NetCDF.", no_args_is_help=True)
stickslip_app = typer.Typer(help="The non-dimensional two-mass stick-slip model (section 4.1.3).", no_args_is_help=True)

app.add_typer(simulate_app, name="simulate")
app.add_typer(sweep_app, name="sweep")
app.add_typer(stickslip_app, name="stickslip")
