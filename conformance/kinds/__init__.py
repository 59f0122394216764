"""Case kinds: each plans the requests its cases need and judges the answers (``core.suite.CaseKind``)."""
