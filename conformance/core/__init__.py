"""The suite-generic core: verdicts, the result model, cases, sessions' contract, the runner.

Nothing here names a protocol or does I/O: suites (``imc_conformance.suites``) bring definitions, codecs
and case kinds; sessions (``imc_conformance.sessions``) talk to implementations; the CLI reads files.
"""
