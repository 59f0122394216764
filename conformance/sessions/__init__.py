"""Sessions: how requests reach an implementation (in-process library, subprocess); they do all the I/O."""
