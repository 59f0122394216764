"""DUNE, LSTS's own IMC node, as a live target: ``make dune`` builds it from the imcpy sdist into the cache,
``make dune-conformance`` runs the scenario set against it in a private network namespace."""
