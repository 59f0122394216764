module example.org/imc-conformance-starter

go 1.21
