"""What every layer shares and nothing physical: user-facing errors (:mod:`.errors`), declared
parameters with units and plausibility ranges (:mod:`.params`), atomic output (:mod:`.io`), the
one registry pattern (:mod:`.registry`) and the source's tables as cited presets
(:mod:`.presets`). It imports nothing else of probedyn."""
