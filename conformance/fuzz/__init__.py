"""Generated cases beyond the corpus: a suite's ``FuzzSource`` (strategies and frame mutations from its definitions)
turned into vector cases, judged through any session by the one runner, shrunk by hypothesis, and promoted into the
corpus. Protocol-free: every suite-specific piece comes from the suite's source."""
