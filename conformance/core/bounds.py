"""The bounds the core itself holds (``limits.py`` lists them with every other bound the suite applies)."""

SHARDS_MAX = 10_000  # shards a selection may be split into (--shard K/N), as a saved result may say
