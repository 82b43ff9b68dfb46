"""conesim planner package."""
