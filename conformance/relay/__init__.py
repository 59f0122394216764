"""The relay between a console and a vehicle: a link that fails as told (impairment), both sides judged (core),
a requester's resending of what the link lost (resend). Sans-IO; ``commands/relay.py`` does the I/O."""
