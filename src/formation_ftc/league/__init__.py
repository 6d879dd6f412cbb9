"""The FTC league: every method on one realistic formation, with the same faults and the same scores."""
