"""Contact mechanics registry (one module per model)."""
