// Placeholder translation unit until the simplifier library's first sources land; delete then.
