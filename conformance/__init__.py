"""imc-conformance: golden vectors and a runner that checks any IMC implementation against them."""

__version__ = "0.1.0"
