; Table clearing by grasping and pushing (after N. Covallero's thesis, 2016, ch. 3).
; One lifted domain for every scene; the problem files list the objects o0..oN-1.
;
; Predicates
;   (on ?a ?b)               a stands on b
;   (block_grasp ?a ?b)      a blocks grasping b: the open gripper at b's grasp pose hits a,
;                            or a reaches into the region its fingers close over
;   (block_dir ?a ?b ?d)     a blocks pushing b along d: b's swept volume or the closed
;                            gripper at b's push pose hits a
;   (removed ?o)             o was grasped and taken off the table (the goal)
;   (ik_unfeasible_grasp ?o), (ik_unfeasible_dir ?o ?d)
;                            no arm configuration reaches the grasp / the push: added by
;                            the planner while backtracking, never by the predicates stage
;   (ungraspable ?o)         static, beyond the thesis: o is wider than the gripper's opening
;                            or narrower than its closing width across the closing direction
;   (push_off_table ?o ?d)   static, beyond the thesis: at the end of the push o's centre
;                            would be off the table polygon
;
; Actions (thesis listings 3.1 and 3.2, with the four push actions made one action with a
; direction parameter):
;   grasp o:  nothing on o, nothing blocks grasping o, reachable, not ungraspable.
;             o is removed; every fact in which o blocks another object or stands on
;             another object is deleted. No IK fact is deleted.
;   push o d: nothing on o, o on nothing, nothing blocks o along d, reachable, not
;             off the table. The planner takes o as pushed far enough to stand alone: every
;             blocking fact o takes part in (either role, any direction) is deleted, and
;             so is (ik_unfeasible_grasp o) (o may be reachable where it ends up).
; Costs: 1 per action (fewest actions, as the thesis). With the clearance-cost setting the
; writer (clearcli.planning.pddl.domain_text(clearance_costs=True)) swaps the push cost for
; (push-cost ?o ?d), a static function the problem sets per object and direction (the
; original code's cost: 1 when the gripper and the swept object keep 0.05 m from the other
; objects, more the closer they come).
; Quantified effects are written flat, (forall (?x - obj ?e - direction) ...): some
; parsers reject a forall nested in an effect.

(define (domain table-clearing)
  (:requirements :typing :negative-preconditions :existential-preconditions
                 :conditional-effects :action-costs)
  (:types obj direction)
  (:constants dir1 dir2 dir3 dir4 - direction)
  (:predicates
    (on ?a - obj ?b - obj)
    (block_grasp ?a - obj ?b - obj)
    (block_dir ?a - obj ?b - obj ?d - direction)
    (removed ?o - obj)
    (ik_unfeasible_grasp ?o - obj)
    (ik_unfeasible_dir ?o - obj ?d - direction)
    (ungraspable ?o - obj)
    (push_off_table ?o - obj ?d - direction))
  (:functions
    (total-cost) - number)

  (:action grasp
    :parameters (?o - obj)
    :precondition (and
      (not (removed ?o))
      (not (ungraspable ?o))
      (not (ik_unfeasible_grasp ?o))
      (not (exists (?x - obj) (on ?x ?o)))
      (not (exists (?x - obj) (block_grasp ?x ?o))))
    :effect (and
      (removed ?o)
      (forall (?x - obj ?e - direction)
        (and (not (on ?o ?x))
             (not (block_grasp ?o ?x))
             (not (block_dir ?o ?x ?e))))
      (increase (total-cost) 1)))

  (:action push
    :parameters (?o - obj ?d - direction)
    :precondition (and
      (not (removed ?o))
      (not (ik_unfeasible_dir ?o ?d))
      (not (push_off_table ?o ?d))
      (not (exists (?x - obj) (block_dir ?x ?o ?d)))
      (not (exists (?x - obj) (on ?x ?o)))
      (not (exists (?x - obj) (on ?o ?x))))
    :effect (and
      (forall (?x - obj ?e - direction)
        (and (not (block_dir ?o ?x ?e))
             (not (block_dir ?x ?o ?e))
             (not (block_grasp ?o ?x))
             (not (block_grasp ?x ?o))))
      (not (ik_unfeasible_grasp ?o))
      (increase (total-cost) 1)))
)
