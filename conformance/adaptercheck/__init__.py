"""adapter-check: an adapter driven through a short, fixed set of requests, each mistake explained with its fix."""
