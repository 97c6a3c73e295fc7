"""Benchmarks: experiment generators writing CSV, Markdown reports, and plots (kept separate)."""
