"""Controller dialects as data."""
