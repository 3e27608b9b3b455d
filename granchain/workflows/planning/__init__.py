"""The planner's parts (granchain.workflows.plan is the planner: plan_scene and the names others import).

choice (PlanChoice: one choice and its reason), travel (the waves' speeds and travel times, the last
measured contact), end_time (the end-time and stop choices: a chain's front, a wall's pulse, the
reflection, one bead's impacts).
"""
