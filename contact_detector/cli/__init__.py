"""Command-line tools: one module per command over the core."""
