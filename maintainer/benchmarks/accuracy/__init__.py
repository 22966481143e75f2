"""Parts of the speed-against-accuracy benchmark (accuracy_vs_cost.py).

Each part is a module with `run(quick, ...) -> {name: rows}` (rows: lists of
dicts with the same keys, written as name.csv) and
`charts(results, outdir) -> [png paths]`."""
