"""Baseline agents that are not the paper's: the uniformly random policy. (ICM and RND are intrinsic rewards, in
:mod:`curiosity.intrinsic`; the Q agent they drive is :mod:`curiosity.agents.q_agent`.)"""
