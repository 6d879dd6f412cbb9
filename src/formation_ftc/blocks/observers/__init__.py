"""Observers (flight side): state / fault estimators driven by measurements and the commanded input."""
