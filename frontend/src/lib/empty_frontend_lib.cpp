// Placeholder translation unit until the frontend library's first sources land; delete then.
