// Placeholder translation unit so the library has a source until mesh/ code lands.
