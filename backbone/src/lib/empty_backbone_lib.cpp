// Placeholder translation unit until the backbone library's first sources land; delete then.
