"""The toolkit's tuning strategies, one module per strategy key of the family contract
(``TuningSpec.strategy``; :data:`tuning.strategy.BUILT_IN`)."""
