"""conesim sim package."""
